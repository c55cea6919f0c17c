// Thread counts: what RenderOptions::threads = 0 ("all cores") means, and how long the library's
// pool threads spin after a job. Read by the library's thread pool (src/core/parallel.hpp), the
// `hsr` command line (the thread count its records name) and the benchmarks.
#pragma once
#include <chrono>
#include <thread>

namespace hsr {

/// How long the pool's threads spin before they sleep: a worker between jobs, the caller of a job
/// for its workers (core/parallel.cpp). A benchmark that times another renderer right after hsr
/// waits this long first, so that no spinning worker takes a core from it.
inline constexpr std::chrono::microseconds kPoolSpin{200};

/// The thread count a request of `requested` threads runs with: `requested` when positive, else
/// (0: all cores) the machine's hardware threads (1 when unknown).
inline int resolveThreads(int requested) {
  if (requested > 0) return requested;
  unsigned n = std::thread::hardware_concurrency();
  return n ? int(n) : 1;
}

}  // namespace hsr
