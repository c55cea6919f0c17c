// The thread pool behind parallelFor (core/parallel.hpp): every index runs exactly once, for any
// count and thread count (each thread takes its own run of indices first, then the others'), a
// call made from inside a task runs on its caller, each thread keeps its part; and WorkQueue's
// lists.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <set>
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

// Jobs apart by less than the pool's spin time (a worker still spinning joins at once), by about
// as much (a worker may see a job end before it joins), and by more (a worker asleep is woken):
// every index still runs once, and a worker takes part in jobs after each kind of gap (three
// times within at most 200 jobs, so that a loaded machine delaying the worker does not fail it).
TEST(Parallel, JobsAfterShortAndLongGaps) {
  using namespace std::chrono;
  constexpr size_t n = 64;
  const bool workers = resolveThreads(0) >= 2;
  for (auto gap : {microseconds(0), microseconds(30), kPoolSpin - microseconds(10), kPoolSpin + microseconds(10),
                   10 * kPoolSpin}) {
    int joined = 0;  // jobs after a gap (not the first) the worker took part in
    for (int job = 0; job < 200 && joined < 3; ++job) {
      std::vector<std::atomic<int>> runs(n);
      std::atomic<bool> other{false};
      parallelFor(0, n, 2, [&](size_t i) {
        const auto until = steady_clock::now() + microseconds(20);  // a task long enough to share
        while (steady_clock::now() < until) {
        }
        if (currentPart() != 0) other = true;
        runs[i].fetch_add(1);
      });
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(runs[i].load(), 1) << "gap " << gap.count() << " us, job " << job;
      if (job > 0 && other.load()) ++joined;
      if (!workers && job >= 20) break;
      std::this_thread::sleep_for(gap);
    }
    if (workers) EXPECT_EQ(joined, 3) << "gap " << gap.count() << " us: the worker did not join";
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

// One thread taking every item through one part: its own list first, in order, then the other
// parts' lists, each in order.
TEST(WorkQueue, OwnListFirstThenTheOthers) {
  WorkQueue q;
  const uint32_t order[] = {4, 0, 6, 2, 5, 1, 3};
  const size_t bounds[] = {0, 3, 3, 7};  // part 0: 4 0 6; part 1: none; part 2: 2 5 1 3
  q.reset(order, 7, bounds, 3);
  std::vector<size_t> got;
  for (size_t i; (i = q.next(2)) < 7;) got.push_back(i);
  EXPECT_EQ(got, (std::vector<size_t>{2, 5, 1, 3, 4, 0, 6}));
  q.reset(order, 7, bounds, 3);
  got.clear();
  for (size_t i; (i = q.next(1)) < 7;) got.push_back(i);
  EXPECT_EQ(got, (std::vector<size_t>{2, 5, 1, 3, 4, 0, 6}));
  // Consecutive runs: 10 items in 3 parts are [0, 4), [4, 8), [8, 10).
  q.reset(10, 3);
  got.clear();
  for (size_t i; (i = q.next(1)) < 10;) got.push_back(i);
  EXPECT_EQ(got, (std::vector<size_t>{4, 5, 6, 7, 8, 9, 0, 1, 2, 3}));
}

TEST(WorkQueue, TwoThreadsTakeEveryItemOnce) {
  for (int round = 0; round < 50; ++round) {
    WorkQueue q;
    std::vector<uint32_t> order(1000);
    for (uint32_t i = 0; i < 1000; ++i) order[i] = (i * 7919u) % 1000u;  // a permutation
    const size_t bounds[] = {0, 100, 1000};
    q.reset(order.data(), order.size(), bounds, 2);
    std::vector<std::atomic<int>> runs(1000);
    auto take = [&](size_t part) {
      for (size_t i; (i = q.next(part)) < 1000;) runs[i].fetch_add(1);
    };
    std::thread other(take, 1);
    take(0);
    other.join();
    for (size_t i = 0; i < runs.size(); ++i) ASSERT_EQ(runs[i].load(), 1) << "round " << round << " item " << i;
  }
}

// The caller is part 0 (also outside any job); each worker always has the same part, below the
// job's thread count.
TEST(Parallel, PartsAreStablePerThread) {
  EXPECT_EQ(currentPart(), 0u);
  const std::thread::id caller = std::this_thread::get_id();
  std::mutex m;
  std::map<std::thread::id, std::set<size_t>> partsOf;
  for (int job = 0; job < 50; ++job)
    parallelFor(0, 16, 2, [&](size_t) {
      const size_t part = currentPart();
      {
        std::lock_guard lock(m);
        partsOf[std::this_thread::get_id()].insert(part);
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));  // (long enough for the worker to join)
    });
  ASSERT_EQ(partsOf.size(), 2u) << "the worker never took part";
  for (const auto& [thread, parts] : partsOf) {
    EXPECT_EQ(parts.size(), 1u);
    EXPECT_LT(*parts.begin(), 2u);
    if (thread == caller) EXPECT_EQ(*parts.begin(), 0u);
    else EXPECT_NE(*parts.begin(), 0u);
  }
  EXPECT_EQ(currentPart(), 0u);
}

}  // namespace
}  // namespace hsr
