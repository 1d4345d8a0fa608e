// Gauss-Seidel sweeps over a graph, on several threads, with the sequential sweeps' result bit for
// bit (the quad remesher's field smoothing, docs/remesh.md "Threads").
//
// A forward sweep visits the vertices 0, 1, ..., n - 1; visiting v reads v's neighbours and writes
// v only, so it sees the neighbours before v already updated in this sweep and those after v not
// yet. Group the vertices into waves: wave(v) = 1 + the largest wave of v's neighbours before v
// (0 when it has none). Then every neighbour before v is in an earlier wave, every neighbour after
// v in a later one, and no two vertices of one wave are neighbours. Visiting the waves in turn,
// each wave's vertices in any order and on any thread, every visit reads exactly what it reads in
// the sequential sweep: the same result. A backward sweep likewise, with "before" and "after"
// exchanged. (Level scheduling of a triangular solve, applied to a nonlinear update.)
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

namespace subd2nurbs {

/// The waves of one sweep's order (above).
struct SweepWaves {
  std::vector<int> order;  ///< the vertices wave by wave; within a wave in sweep order
  std::vector<int> begin;  ///< wave k is order[begin[k] .. begin[k + 1])
  int count() const { return static_cast<int>(begin.size()) - 1; }
};

/// The waves of the forward (vertex 0 first) or backward sweep over the graph of n =
/// offsets.size() - 1 vertices whose neighbours of v are adj[offsets[v] .. offsets[v + 1]).
inline SweepWaves sweep_waves(const std::vector<int>& offsets, const std::vector<int>& adj, bool forward) {
  const int n = static_cast<int>(offsets.size()) - 1;
  std::vector<int> wave(static_cast<std::size_t>(std::max(n, 0)), 0);
  int waves = 0;
  for (int k = 0; k < n; ++k) {
    const int v = forward ? k : n - 1 - k;
    int w = 0;
    for (int i = offsets[v]; i < offsets[v + 1]; ++i) {
      const int u = adj[i];
      if (forward ? u < v : u > v) w = std::max(w, wave[u] + 1);
    }
    wave[v] = w;
    waves = std::max(waves, w + 1);
  }
  SweepWaves r;
  r.begin.assign(static_cast<std::size_t>(waves) + 1, 0);
  for (int v = 0; v < n; ++v) ++r.begin[wave[v] + 1];
  for (int k = 0; k < waves; ++k) r.begin[k + 1] += r.begin[k];
  std::vector<int> fill(r.begin.begin(), r.begin.end() - 1);
  r.order.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const int v = forward ? k : n - 1 - k;
    r.order[fill[wave[v]]++] = v;
  }
  return r;
}

/// A barrier for a fixed number of threads that spins briefly, then yields (the machines are
/// shared: a waiting thread must not hold a core the others need).
class SpinBarrier {
 public:
  explicit SpinBarrier(int threads) : threads_(threads), waiting_(threads) {}
  void wait() {
    const int generation = generation_.load(std::memory_order_acquire);
    if (waiting_.fetch_sub(1, std::memory_order_acq_rel) == 1) {  // the last to arrive
      waiting_.store(threads_, std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_release);
      return;
    }
    for (int spins = 0; generation_.load(std::memory_order_acquire) == generation; ++spins)
      if (spins >= 256) std::this_thread::yield();
  }

 private:
  const int threads_;
  std::atomic<int> waiting_;
  std::atomic<int> generation_{0};
};

/// Waves narrower than this per thread on average: the sweeps stay on one thread (the barriers
/// would cost more than the shared work saves). At 8, fandisk.off's remesh, whose dense level
/// has waves of 21 vertices on average, took 0.52 -> 0.35 s on two threads (medians of 5).
constexpr int kMinWavePerThread = 8;

/// `iterations` Gauss-Seidel sweeps over the graph (offsets, adj as in sweep_waves), forwards and
/// backwards in turn, on up to `threads` threads: visit(v) smooths vertex v (reading its
/// neighbours, writing only v's own data); prefetch(w) is called for each neighbour w of the
/// vertex a thread visits two after this one (a hint: bring what visit reads of w into the
/// cache); after each sweep, after_sweep() runs on the calling thread (it may throw, e.g. a
/// cancel: the other threads then stop and the exception is rethrown). The result is the
/// sequential sweeps' whatever the thread count (the waves above). Returns the threads used: 1
/// when the waves are too narrow to share (kMinWavePerThread) or the graph too small.
template <class Visit, class Prefetch, class AfterSweep>
int gauss_seidel_sweeps(const std::vector<int>& offsets, const std::vector<int>& adj, int iterations, int threads,
                         Visit&& visit, Prefetch&& prefetch, AfterSweep&& after_sweep) {
  const int n = static_cast<int>(offsets.size()) - 1;
  auto fetch_neighbours = [&](int w) {
    for (int i = offsets[w]; i < offsets[w + 1]; ++i) prefetch(adj[i]);
  };
  SweepWaves waves[2];
  if (n < 2 * kMinWavePerThread * threads) threads = 1;  // too few vertices to share
  if (threads > 1) {  // as many threads as the waves are wide enough for
    waves[0] = sweep_waves(offsets, adj, true);
    waves[1] = sweep_waves(offsets, adj, false);
    const int deepest = std::max(waves[0].count(), waves[1].count());
    threads = std::min(threads, n / (std::max(deepest, 1) * kMinWavePerThread));
  }
  if (threads <= 1) {
    for (int it = 0; it < iterations; ++it) {
      const int step = it % 2 == 0 ? 1 : -1;
      for (int k = 0; k < n; ++k) {
        const int v = step > 0 ? k : n - 1 - k;
        const int ahead = v + 2 * step;
        if (ahead >= 0 && ahead < n) fetch_neighbours(ahead);
        visit(v);
      }
      after_sweep();
    }
    return 1;
  }
  SpinBarrier barrier(threads);
  std::exception_ptr error;  // after_sweep's, set by the calling thread before a barrier
  auto work = [&](int t) {
    for (int it = 0; it < iterations; ++it) {
      const SweepWaves& w = waves[it % 2];
      for (int k = 0; k < w.count(); ++k) {
        const int size = w.begin[k + 1] - w.begin[k];
        const int lo = w.begin[k] + static_cast<int>(static_cast<long long>(size) * t / threads);
        const int hi = w.begin[k] + static_cast<int>(static_cast<long long>(size) * (t + 1) / threads);
        for (int j = lo; j < hi; ++j) {
          if (j + 2 < hi) fetch_neighbours(w.order[j + 2]);
          visit(w.order[j]);
        }
        barrier.wait();
      }
      if (t == 0) {
        try {
          after_sweep();
        } catch (...) {
          error = std::current_exception();
        }
      }
      barrier.wait();  // every thread sees `error` as the calling thread left it
      if (error) return;
    }
  };
  std::vector<std::thread> helpers;
  for (int t = 1; t < threads; ++t) helpers.emplace_back(work, t);
  work(0);
  for (std::thread& h : helpers) h.join();
  if (error) std::rethrow_exception(error);
  return threads;
}

}  // namespace subd2nurbs
