// Deterministic parallel-for over an index range on a persistent thread pool, used by callers
// (the front end, the tiled z-buffer's tile loop, the ray caster's rows, buffer clears), never
// inside an algorithm's inner loop. Work items are fixed by the caller, so results never depend
// on the thread count as long as each index writes only its own outputs.
#pragma once
#include <cstddef>
#include <functional>
#include <thread>

namespace hsr {

inline int resolveThreads(int requested) {
  if (requested > 0) return requested;
  unsigned n = std::thread::hardware_concurrency();
  return n ? int(n) : 1;
}

/// Runs task(i) for i in [0, n) on the calling thread plus up to threads - 1 pool workers
/// (the pool has hardware_concurrency - 1 of them, started once). Each thread takes a block of
/// consecutive indices first (the caller the first block), then helps with the others'. A call
/// made while another is running (nested, or from another thread) runs serially on its caller.
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
