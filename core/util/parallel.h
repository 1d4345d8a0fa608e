// A minimal parallel loop for independent work items (one per coarse face or vertex).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace subd2nurbs {

/// The machine's hardware threads (at least 1), asked once.
inline int hardware_threads() {
  static const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return threads;
}

/// The most threads the parallel loops started from the calling thread may use; 0: as many as
/// the machine has. Set for a scope with ThreadLimit; each thread has its own.
inline int& thread_limit() {
  thread_local int limit = 0;
  return limit;
}

/// Limits the parallel loops the calling thread starts while it lives to `threads` threads (the
/// `threads` setting: several conversions running side by side, each on one core, outrun one
/// conversion on all of them). threads <= 0 keeps the limit in force. A thread that works
/// beside the caller for the same job takes the caller's limit (`ThreadLimit scope(limit)` with
/// the value read from thread_limit() before it started).
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads) : previous_(thread_limit()) {
    if (threads > 0) thread_limit() = threads;
  }
  ~ThreadLimit() { thread_limit() = previous_; }
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  int previous_;
};

/// The jobs (conversions) running at once in this process, each counted once (JobShare).
inline std::atomic<int>& running_jobs() {
  static std::atomic<int> jobs{0};
  return jobs;
}

/// Counts the calling thread's job among the running ones while it lives (nested scopes on one
/// thread count once): parallel loops without a ThreadLimit share the hardware threads among
/// the jobs running when they start, so that several Python threads converting at once do
/// not each spread over every core.
class JobShare {
 public:
  JobShare() : counted_(depth()++ == 0) {
    if (counted_) running_jobs().fetch_add(1);
  }
  ~JobShare() {
    --depth();
    if (counted_) running_jobs().fetch_sub(1);
  }
  JobShare(const JobShare&) = delete;
  JobShare& operator=(const JobShare&) = delete;

 private:
  static int& depth() {
    thread_local int d = 0;
    return d;
  }
  bool counted_;
};

/// The threads a parallel loop started on the calling thread uses at most: its ThreadLimit
/// (at most the hardware threads), else the hardware threads shared by the running jobs
/// (at least 1).
inline int loop_threads() {
  const int limit = thread_limit();
  if (limit > 0) return std::min(limit, hardware_threads());
  return std::max(1, hardware_threads() / std::max(1, running_jobs().load()));
}

/// The threads that single-threaded work running beside parallel loops has taken
/// (ThreadReservation).
inline std::atomic<int>& reserved_threads() {
  static std::atomic<int> reserved{0};
  return reserved;
}

/// Takes one hardware thread for the calling thread's own single-threaded work while it lives:
/// parallel loops started meanwhile (on other threads) use one thread fewer, so that the two
/// do not share a core. The count is process-wide.
class ThreadReservation {
 public:
  ThreadReservation() { reserved_threads().fetch_add(1); }
  ~ThreadReservation() { reserved_threads().fetch_sub(1); }
  ThreadReservation(const ThreadReservation&) = delete;
  ThreadReservation& operator=(const ThreadReservation&) = delete;
};

/// The threads a parallel loop started now may use: the hardware threads not reserved, at
/// least 1.
inline int available_threads() { return std::max(1, hardware_threads() - reserved_threads().load()); }

/// Calls fn(i) for i in [0, n) on up to loop_threads() threads, items handed out in runs of
/// consecutive indices (about 16 runs per thread, at most 64 items each): one atomic step per run, and
/// neighbouring slots written by one thread. fn must only write to its own item's slot. The
/// first exception thrown is rethrown once every thread has stopped. Results are independent of
/// the thread count.
///
/// Only available_threads() of them take runs at any time: while other work holds a
/// ThreadReservation, the helper threads beyond that wait (waking every millisecond), and they
/// join in as soon as the reservation ends. The calling thread always works. A loop that fn
/// starts on a helper thread stays on that thread (the helpers have a limit of 1); on the
/// calling thread it gets the caller's limit.
template <class Fn>
void parallel_for(int n, Fn&& fn) {
  const int threads = std::min(loop_threads(), std::max(1, n / 16));
  if (threads <= 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  const int run = std::clamp(n / (16 * threads), 1, 64);
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](int thread) {
    const ThreadLimit nested(thread == 0 ? 0 : 1);  // a helper's nested loops stay on it
    for (;;) {
      if (thread >= available_threads()) {  // this helper's core is reserved meanwhile
        if (next.load() >= n) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      const int begin = next.fetch_add(run);
      if (begin >= n) return;
      const int end = std::min(n, begin + run);
      try {
        for (int i = begin; i < end; ++i) fn(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace subd2nurbs
