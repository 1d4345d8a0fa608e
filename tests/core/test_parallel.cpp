// parallel_for: every item once, exceptions passed on, and the threads it uses: at most the
// hardware threads not reserved (ThreadReservation), so that a loop running beside
// single-threaded work (the quality stage beside OCCT's B-rep and file writing) does not take
// that work's core.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/util/parallel.h"

namespace subd2nurbs {
namespace {

/// The distinct threads that ran items of a loop of `n` slow items.
std::set<std::thread::id> threads_used(int n) {
  std::set<std::thread::id> ids;
  std::mutex m;
  parallel_for(n, [&](int) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));  // long enough for every thread to take runs
    std::lock_guard<std::mutex> lock(m);
    ids.insert(std::this_thread::get_id());
  });
  return ids;
}

TEST(ParallelFor, EveryItemOnceAndTheFirstExceptionPassedOn) {
  std::vector<int> hits(10000, 0);
  parallel_for(static_cast<int>(hits.size()), [&](int i) { ++hits[i]; });
  for (size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i], 1) << "item " << i;
  EXPECT_THROW(parallel_for(1000, [](int i) {
                 if (i == 517) throw std::runtime_error("item 517");
               }),
               std::runtime_error);
}

TEST(ParallelFor, LeavesReservedThreadsTheirCores) {
  const int hardware = hardware_threads();
  EXPECT_EQ(available_threads(), hardware);
  if (hardware >= 2) EXPECT_EQ(threads_used(200).size(), static_cast<size_t>(std::min(hardware, 200 / 16)));
  {
    const ThreadReservation occt_core;
    EXPECT_EQ(available_threads(), std::max(1, hardware - 1));
    // The loop is started on another thread, as the quality stage is while the reserving
    // thread works.
    std::set<std::thread::id> ids;
    std::thread beside([&] { ids = threads_used(200); });
    beside.join();
    EXPECT_EQ(ids.size(), static_cast<size_t>(std::max(1, hardware - 1)));
    {
      const ThreadReservation second;
      EXPECT_EQ(available_threads(), std::max(1, hardware - 2));  // never below 1
    }
    EXPECT_EQ(available_threads(), std::max(1, hardware - 1));
  }
  EXPECT_EQ(available_threads(), hardware);
}

TEST(ParallelFor, HelpersJoinInWhenTheReservationEnds) {
  const int hardware = hardware_threads();
  // A loop of 200 ms on one thread starts while a core is reserved; the reservation ends after
  // 20 ms, and the waiting helpers take the rest with the calling thread.
  auto reservation = std::make_unique<ThreadReservation>();
  std::set<std::thread::id> ids;
  std::thread beside([&] { ids = threads_used(200); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  reservation.reset();
  beside.join();
  EXPECT_EQ(ids.size(), static_cast<size_t>(std::min(hardware, 200 / 16)));
}

TEST(ParallelFor, ThreadLimitKeepsLoopsOnTheCallingThread) {
  const int hardware = hardware_threads();
  EXPECT_EQ(loop_threads(), hardware);
  {
    const ThreadLimit one(1);
    EXPECT_EQ(loop_threads(), 1);
    const std::set<std::thread::id> ids = threads_used(200);
    ASSERT_EQ(ids.size(), 1u);
    EXPECT_EQ(*ids.begin(), std::this_thread::get_id());
    // The limit is the calling thread's: a loop started on another thread uses every core.
    std::set<std::thread::id> other;
    std::thread beside([&] { other = threads_used(200); });
    beside.join();
    EXPECT_EQ(other.size(), static_cast<size_t>(std::min(hardware, 200 / 16)));
    {
      const ThreadLimit keep(0);  // 0 keeps the limit in force
      EXPECT_EQ(loop_threads(), 1);
      const ThreadLimit more(1000);  // never beyond the hardware
      EXPECT_EQ(loop_threads(), hardware);
    }
    EXPECT_EQ(loop_threads(), 1);  // restored when the inner scopes end
  }
  EXPECT_EQ(loop_threads(), hardware);
}

TEST(ParallelFor, RunningJobsShareTheCores) {
  const int hardware = hardware_threads();
  EXPECT_EQ(running_jobs().load(), 0);
  {
    const JobShare first;
    const JobShare nested;  // the same thread's job: counted once
    EXPECT_EQ(running_jobs().load(), 1);
    EXPECT_EQ(loop_threads(), hardware);
    std::atomic<bool> started{false}, done{false};
    std::thread other([&] {
      const JobShare second;
      started = true;
      while (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    });
    while (!started) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    EXPECT_EQ(running_jobs().load(), 2);
    EXPECT_EQ(loop_threads(), std::max(1, hardware / 2));
    EXPECT_EQ(threads_used(200).size(), static_cast<size_t>(std::min(std::max(1, hardware / 2), 200 / 16)));
    {
      const ThreadLimit given(hardware);  // a ThreadLimit is the caller's own choice
      EXPECT_EQ(loop_threads(), hardware);
    }
    done = true;
    other.join();
    EXPECT_EQ(loop_threads(), hardware);
  }
  EXPECT_EQ(running_jobs().load(), 0);
}

TEST(ParallelFor, LoopsInsideALoopStayOnTheirThread) {
  // Each item of the outer loop starts a loop of its own; those run on the thread that runs the
  // item (the helpers have a limit of 1; the calling thread keeps its own).
  std::vector<int> nested_threads(64, 0);
  std::vector<int> limit_seen(64, -1);
  std::vector<char> on_caller(64, 0);
  const std::thread::id caller = std::this_thread::get_id();
  parallel_for(64, [&](int i) {
    std::set<std::thread::id> ids;
    std::mutex m;
    const bool main_thread = std::this_thread::get_id() == caller;
    on_caller[i] = main_thread;
    limit_seen[i] = loop_threads();
    parallel_for(32, [&](int) {
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    });
    nested_threads[i] = static_cast<int>(ids.size());
  });
  for (int i = 0; i < 64; ++i) {
    if (on_caller[i]) continue;
    EXPECT_EQ(limit_seen[i], 1) << "item " << i;
    EXPECT_EQ(nested_threads[i], 1) << "item " << i;
  }
}

}  // namespace
}  // namespace subd2nurbs
