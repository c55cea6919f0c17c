// Deterministic parallel-for over an index range on a persistent thread pool, used by callers
// (the front end, the tiled z-buffer's tile loop, the ray caster's rows, buffer clears), never
// inside an algorithm's inner loop. Work items are fixed by the caller, so results never depend
// on the thread count as long as each index writes only its own outputs.
#pragma once
#include <hsr/threads.hpp>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

namespace hsr {

/// Work items [0, n) shared out among the `parts` threads of a parallel job (currentPart), each
/// part with its own list: a thread takes the items of its own list first, in order, then helps
/// with the others' (next). So a pass can give each thread the items whose data the same thread
/// wrote in an earlier pass, still in its core's caches; on a machine whose cores do not share a
/// last-level cache (a line written by the other core costs several times as much to load as
/// one of its own; see docs/benchmarks.md) that decides much of a frame's time.
/// Reused from job to job (no allocation once warm).
class WorkQueue {
 public:
  /// [0, n) in `parts` (>= 1) lists of consecutive items: part p's are the p-th of `parts` runs.
  void reset(size_t n, size_t parts);
  /// The items order[0, n) (a permutation of [0, n)), part p's list order[bounds[p], bounds[p + 1]).
  void reset(const uint32_t* order, size_t n, const size_t* bounds, size_t parts);
  /// n: the items are [0, n).
  size_t size() const { return n_; }
  /// The next item for thread `part` (< parts), or n when every item is taken. Not while reset() runs.
  size_t next(size_t part) {
    for (size_t k = 0; k < parts_; ++k) {
      List& l = lists_[part + k < parts_ ? part + k : part + k - parts_];
      if (l.next.load(std::memory_order_relaxed) >= l.end) continue;  // (taken: no write to a line others read)
      const size_t i = l.next.fetch_add(1, std::memory_order_relaxed);
      if (i < l.end) return order_.empty() ? i : order_[i];
    }
    return n_;
  }

 private:
  struct alignas(64) List {  // a cache line each: the threads' counters never share one
    std::atomic<size_t> next{0};
    size_t end = 0;
  };
  void setParts(size_t parts);
  std::unique_ptr<List[]> lists_;
  std::vector<uint32_t> order_;  // empty: item i is i
  size_t capacity_ = 0, parts_ = 0, n_ = 0;
};

/// The part the calling thread takes in the parallel job it runs: 0 for the thread that called
/// runParallel (and outside any job), 1, 2, ... for the pool's workers, each always the same
/// thread; a job of at most k threads has parts [0, k).
size_t currentPart();

/// Runs task(i) for i in [0, n) on the calling thread plus up to threads - 1 pool workers
/// (the pool has hardware_concurrency - 1 of them, started once), the items shared out by a
/// WorkQueue in runs of consecutive indices: thread by thread, the same runs job after job, so
/// a thread's tasks mostly read what its own earlier tasks wrote for nearby indices (the front
/// end's triangle chunks, the vertices its vertex chunks projected), which is faster than one
/// shared counter. A call made while another is running (nested, or from another thread) runs
/// serially on its caller.
void runParallel(size_t n, int threads, const std::function<void(size_t)>& task);

/// Calls fn(i) for i in [begin, end) on up to `threads` threads.
template <class Fn>
void parallelFor(size_t begin, size_t end, int threads, Fn&& fn) {
  if (end <= begin) return;
  if (threads <= 1 || end - begin == 1) {
    for (size_t i = begin; i < end; ++i) fn(i);
    return;
  }
  runParallel(end - begin, threads, [&](size_t i) { fn(begin + i); });
}

}  // namespace hsr
