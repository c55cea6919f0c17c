// A tiny deterministic parallel-for over an index range, used by callers (never inside algorithm
// inner loops). Work is split into fixed chunks, so results never depend on the thread count as
// long as each index writes only its own outputs.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace hsr {

inline int resolveThreads(int requested) {
  if (requested > 0) return requested;
  unsigned n = std::thread::hardware_concurrency();
  return n ? int(n) : 1;
}

/// Calls fn(i) for i in [begin, end) on up to `threads` threads.
template <class Fn>
void parallelFor(size_t begin, size_t end, int threads, Fn&& fn) {
  threads = std::max(1, threads);
  size_t n = end > begin ? end - begin : 0;
  if (threads == 1 || n < 2) {
    for (size_t i = begin; i < end; ++i) fn(i);
    return;
  }
  std::atomic<size_t> next{begin};
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < end;) fn(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads && size_t(t) < n; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace hsr
