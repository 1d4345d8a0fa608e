// Gauss-Seidel sweeps on several threads (core/util/wave_sweeps.h): the waves order every edge as
// the sweep does, and the threaded sweeps equal a plain sequential loop bit for bit on an update
// whose result depends on the visiting order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/util/wave_sweeps.h"

namespace subd2nurbs {
namespace {

struct Graph {
  std::vector<int> offsets, adj;  // CSR, sorted neighbours, no self loops
  int n() const { return static_cast<int>(offsets.size()) - 1; }
};

Graph from_edges(int n, const std::vector<std::pair<int, int>>& edges) {
  std::vector<std::set<int>> nb(static_cast<size_t>(n));
  for (auto [a, b] : edges)
    if (a != b) nb[a].insert(b), nb[b].insert(a);
  Graph g;
  g.offsets.push_back(0);
  for (const auto& s : nb) {
    g.adj.insert(g.adj.end(), s.begin(), s.end());
    g.offsets.push_back(static_cast<int>(g.adj.size()));
  }
  return g;
}

// A triangulated w x h grid whose vertex labels are shuffled (as an STL's welded vertices are
// scattered over the surface): wide waves.
Graph shuffled_grid(int w, int h, unsigned seed) {
  std::vector<int> label(static_cast<size_t>(w * h));
  for (int i = 0; i < w * h; ++i) label[i] = i;
  std::shuffle(label.begin(), label.end(), std::mt19937(seed));
  std::vector<std::pair<int, int>> edges;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int v = label[y * w + x];
      if (x + 1 < w) edges.push_back({v, label[y * w + x + 1]});
      if (y + 1 < h) edges.push_back({v, label[(y + 1) * w + x]});
      if (x + 1 < w && y + 1 < h) edges.push_back({v, label[(y + 1) * w + x + 1]});
    }
  return from_edges(w * h, edges);
}

Graph path(int n) {
  std::vector<std::pair<int, int>> edges;
  for (int i = 0; i + 1 < n; ++i) edges.push_back({i, i + 1});
  return from_edges(n, edges);
}

// The update: v's new value from its own and its neighbours' present values, nonlinear and
// order-dependent (a Jacobi sweep or a wrong order gives other bits).
double update(const Graph& g, const std::vector<double>& x, int v) {
  double sum = std::sin(x[v]);
  for (int i = g.offsets[v]; i < g.offsets[v + 1]; ++i) {
    const int u = g.adj[i];
    sum = 0.7 * sum + 0.3 * std::cos(x[u] + 0.01 * u);
  }
  return sum;
}

std::vector<double> start_values(int n) {
  std::vector<double> x(static_cast<size_t>(n));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-2, 2);
  for (double& xi : x) xi = d(rng);
  return x;
}

// The oracle: forwards, backwards, ... one vertex after the other.
std::vector<double> sequential(const Graph& g, int iterations) {
  std::vector<double> x = start_values(g.n());
  for (int it = 0; it < iterations; ++it)
    for (int k = 0; k < g.n(); ++k) {
      const int v = it % 2 == 0 ? k : g.n() - 1 - k;
      x[v] = update(g, x, v);
    }
  return x;
}

TEST(WaveSweeps, EveryEdgeRunsFromAnEarlierWaveInSweepOrder) {
  for (const Graph& g : {shuffled_grid(60, 50, 1), path(200)}) {
    for (bool forward : {true, false}) {
      const SweepWaves w = sweep_waves(g.offsets, g.adj, forward);
      ASSERT_EQ(w.order.size(), static_cast<size_t>(g.n()));
      std::vector<int> wave_of(static_cast<size_t>(g.n()), -1);
      for (int k = 0; k < w.count(); ++k) {
        ASSERT_LT(w.begin[k], w.begin[k + 1]) << "wave " << k << " is empty";
        for (int j = w.begin[k]; j < w.begin[k + 1]; ++j) {
          ASSERT_EQ(wave_of[w.order[j]], -1) << "vertex " << w.order[j] << " twice";
          wave_of[w.order[j]] = k;
        }
      }
      for (int v = 0; v < g.n(); ++v)
        for (int i = g.offsets[v]; i < g.offsets[v + 1]; ++i) {
          const int u = g.adj[i];
          const bool u_first = forward ? u < v : u > v;
          if (u_first) EXPECT_LT(wave_of[u], wave_of[v]) << "edge " << u << "-" << v;
        }
    }
  }
  // A path visited in its own order: each vertex waits for the one before it.
  EXPECT_EQ(sweep_waves(path(200).offsets, path(200).adj, true).count(), 200);
  // The shuffled grid: a few dozen waves for 3000 vertices (what makes sharing worth it).
  const Graph grid = shuffled_grid(60, 50, 1);
  EXPECT_LT(sweep_waves(grid.offsets, grid.adj, true).count(), 60);
}

TEST(WaveSweeps, ThreadsGiveTheSequentialResultBitForBit) {
  const Graph g = shuffled_grid(120, 100, 3);
  const int iterations = 7;  // odd: ends on a forward sweep
  const std::vector<double> expected = sequential(g, iterations);
  // A Jacobi-like order gives other values: the comparison can fail.
  {
    std::vector<double> x = start_values(g.n()), next(x.size());
    for (int v = 0; v < g.n(); ++v) next[v] = update(g, x, v);
    EXPECT_NE(std::memcmp(next.data(), sequential(g, 1).data(), sizeof(double) * next.size()), 0);
  }
  for (int threads : {1, 2, 4}) {
    std::vector<double> x = start_values(g.n());
    std::vector<std::thread::id> who(x.size());
    int sweeps_done = 0;
    const int used = gauss_seidel_sweeps(
        g.offsets, g.adj, iterations, threads,
        [&](int v) {
          x[v] = update(g, x, v);
          who[v] = std::this_thread::get_id();
        },
        [&](int w) { __builtin_prefetch(&x[w]); }, [&] { ++sweeps_done; });
    EXPECT_EQ(used, threads);
    EXPECT_EQ(sweeps_done, iterations);
    EXPECT_EQ(std::memcmp(x.data(), expected.data(), sizeof(double) * x.size()), 0) << threads << " threads";
    EXPECT_EQ(std::set<std::thread::id>(who.begin(), who.end()).size(), static_cast<size_t>(threads));
  }
}

TEST(WaveSweeps, NarrowWavesStayOnTheCallingThread) {
  const Graph g = path(5000);  // 5000 waves of one vertex
  std::vector<double> x = start_values(g.n());
  std::set<std::thread::id> who;
  const int used = gauss_seidel_sweeps(
      g.offsets, g.adj, 4, 2, [&](int v) { x[v] = update(g, x, v), who.insert(std::this_thread::get_id()); },
      [](int) {}, [] {});
  EXPECT_EQ(used, 1);
  EXPECT_EQ(who, std::set<std::thread::id>{std::this_thread::get_id()});
  EXPECT_EQ(std::memcmp(x.data(), sequential(g, 4).data(), sizeof(double) * x.size()), 0);
}

TEST(WaveSweeps, AnExceptionAfterASweepStopsEveryThread) {
  const Graph g = shuffled_grid(100, 100, 5);
  std::vector<double> x = start_values(g.n());
  int sweeps_done = 0;
  EXPECT_THROW(gauss_seidel_sweeps(
                   g.offsets, g.adj, 30, 2, [&](int v) { x[v] = update(g, x, v); }, [](int) {},
                   [&] {
                     if (++sweeps_done == 3) throw std::runtime_error("cancelled");
                   }),
               std::runtime_error);
  EXPECT_EQ(sweeps_done, 3);  // no sweep after the throw
  EXPECT_EQ(std::memcmp(x.data(), sequential(g, 3).data(), sizeof(double) * x.size()), 0);
}

}  // namespace
}  // namespace subd2nurbs
