// The thread pool behind parallelFor (core/parallel.hpp): every index runs exactly once, for any
// count and thread count (each thread takes its own block of indices first, then the others'),
// and a call made from inside a task runs on its caller.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "core/parallel.hpp"

namespace hsr {
namespace {

TEST(Parallel, EveryIndexRunsExactlyOnce) {
  for (int threads : {1, 2, 3, 4, 8}) {
    for (size_t n : {size_t(1), size_t(2), size_t(3), size_t(5), size_t(64), size_t(1001)}) {
      std::unique_ptr<std::atomic<int>[]> runs(new std::atomic<int>[n]);
      for (size_t i = 0; i < n; ++i) runs[i] = 0;
      parallelFor(0, n, threads, [&](size_t i) { runs[i].fetch_add(1); });
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(runs[i].load(), 1) << "index " << i << " of " << n << ", " << threads << " threads";
    }
  }
}

TEST(Parallel, OffsetRangeAndEmptyRange) {
  std::vector<std::atomic<int>> runs(40);
  parallelFor(10, 40, 2, [&](size_t i) { runs[i].fetch_add(1); });
  for (size_t i = 0; i < 40; ++i) EXPECT_EQ(runs[i].load(), i >= 10 ? 1 : 0) << i;
  bool ran = false;
  parallelFor(5, 5, 2, [&](size_t) { ran = true; });
  EXPECT_FALSE(ran);
}

// Jobs back to back (as a frame runs them), with tasks of uneven cost: a thread that finishes its
// own block helps with the others', so every index still runs once.
TEST(Parallel, ManyJobsWithUnevenTasks) {
  constexpr size_t n = 97;
  for (int job = 0; job < 200; ++job) {
    std::vector<std::atomic<int>> runs(n);
    parallelFor(0, n, 2, [&](size_t i) {
      if (i < n / 2 && job % 2 == 0) std::this_thread::yield();  // the first block slower
      runs[i].fetch_add(1);
    });
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(runs[i].load(), 1) << "job " << job << " index " << i;
  }
}

TEST(Parallel, NestedCallRunsOnItsCaller) {
  std::vector<std::atomic<int>> runs(8 * 8);
  parallelFor(0, 8, 2, [&](size_t outer) {
    const std::thread::id caller = std::this_thread::get_id();
    parallelFor(0, 8, 2, [&](size_t inner) {
      EXPECT_EQ(std::this_thread::get_id(), caller);
      runs[outer * 8 + inner].fetch_add(1);
    });
  });
  for (size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i].load(), 1) << i;
}

}  // namespace
}  // namespace hsr
