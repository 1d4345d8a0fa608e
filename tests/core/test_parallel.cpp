// parallel_for: every item once, exceptions passed on, and the threads it uses: at most the
// hardware threads not reserved (ThreadReservation), so that a loop running beside
// single-threaded work (the quality stage beside OCCT's B-rep and file writing) does not take
// that work's core.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace subd2nurbs
