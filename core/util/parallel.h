// A minimal parallel loop for independent work items (one per coarse face or vertex).
#pragma once

#include <algorithm>
#include <atomic>
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

/// Calls fn(i) for i in [0, n) on up to hardware_threads() threads, items handed out in runs of
/// consecutive indices (about 16 runs per thread, at most 64 items each): one atomic step per run, and
/// neighbouring slots written by one thread. fn must only write to its own item's slot. The
/// first exception thrown is rethrown once every thread has stopped. Results are independent of
/// the thread count.
template <class Fn>
void parallel_for(int n, Fn&& fn) {
  const int threads = std::min(hardware_threads(), std::max(1, n / 16));
  if (threads <= 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  const int run = std::clamp(n / (16 * threads), 1, 64);
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (int begin = next.fetch_add(run); begin < n; begin = next.fetch_add(run)) {
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
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace subd2nurbs
