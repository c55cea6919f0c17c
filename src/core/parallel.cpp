// The persistent thread pool behind parallelFor (see parallel.hpp). Workers sleep on a
// condition variable between jobs; a job hands out its indices in one block per thread
// (BlockedIndices).
#include "core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

namespace hsr {
namespace {

// Indices [0, n) shared out among `parts` threads in blocks of consecutive indices, one block
// per part: a thread takes the indices of its own block first, in order, then helps with the
// others' (next). The pool's threads keep their parts from job to job (the caller is part 0,
// the workers 1, 2, ... in the order they join), so a thread mostly reads what it wrote itself
// in the job before for nearby indices, from its own core's caches: the front end's triangle
// chunks read the projected vertices of the same part of the mesh that its vertex chunks wrote
// (sphere frames 0.96 of the time with two threads, against one shared counter; the tile pass
// handing each worker its own half of the image gained nothing more, and keeps its counter).
class BlockedIndices {
 public:
  // Starts handing out [0, n) to `parts` (>= 1) threads; not while any thread calls next().
  void reset(size_t n, size_t parts) {
    if (parts > capacity_) {
      blocks_.reset(new Block[parts]);
      capacity_ = parts;
    }
    parts_ = parts;
    n_ = n;
    const size_t size = (n + parts - 1) / parts;
    for (size_t b = 0; b < parts; ++b) {
      blocks_[b].next.store(std::min(n, b * size), std::memory_order_relaxed);
      blocks_[b].end = std::min(n, (b + 1) * size);
    }
  }
  // The next index for thread `part` (< parts), or n when every index is taken.
  size_t next(size_t part) {
    for (size_t k = 0; k < parts_; ++k) {
      Block& b = blocks_[part + k < parts_ ? part + k : part + k - parts_];
      if (b.next.load(std::memory_order_relaxed) >= b.end) continue;  // (taken: no write to a line others read)
      const size_t i = b.next.fetch_add(1, std::memory_order_relaxed);
      if (i < b.end) return i;
    }
    return n_;
  }

 private:
  struct alignas(64) Block {  // a cache line each: the threads' counters never share one
    std::atomic<size_t> next{0};
    size_t end = 0;
  };
  std::unique_ptr<Block[]> blocks_;
  size_t capacity_ = 0, parts_ = 0, n_ = 0;
};

class ThreadPool {
 public:
  ThreadPool() {
    const int workers = std::max(1, resolveThreads(0) - 1);
    for (int i = 0; i < workers; ++i) threads_.emplace_back([this] { work(); });
  }
  ~ThreadPool() {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }

  void run(size_t n, int threads, const std::function<void(size_t)>& task) {
    std::unique_lock job(jobMutex_, std::try_to_lock);
    if (!job.owns_lock()) {  // nested or concurrent: this caller does the work alone
      for (size_t i = 0; i < n; ++i) task(i);
      return;
    }
    {
      std::lock_guard lock(m_);
      task_ = &task;
      admit_ = int(std::min<size_t>({size_t(threads - 1), threads_.size(), n - 1}));
      indices_.reset(n, size_t(admit_) + 1);
      end_ = n;
      joined_ = 0;
      ++generation_;
    }
    wake_.notify_all();
    drain(0);
    std::unique_lock lock(m_);
    admit_ = joined_;  // no worker may join after this: task_ is about to go out of scope
    done_.wait(lock, [&] { return active_ == 0; });
    task_ = nullptr;
  }

 private:
  void drain(size_t part) {
    for (size_t i; (i = indices_.next(part)) < end_;) (*task_)(i);
  }
  void work() {
    uint64_t seen = 0;
    std::unique_lock lock(m_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || (generation_ != seen && joined_ < admit_); });
      if (stop_) return;
      seen = generation_;
      const size_t part = size_t(++joined_);
      ++active_;
      lock.unlock();
      drain(part);
      lock.lock();
      if (--active_ == 0) done_.notify_all();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex jobMutex_;  // one job at a time
  std::mutex m_;
  std::condition_variable wake_, done_;
  const std::function<void(size_t)>* task_ = nullptr;
  BlockedIndices indices_;
  size_t end_ = 0;
  int admit_ = 0, joined_ = 0, active_ = 0;
  uint64_t generation_ = 0;
  bool stop_ = false;
};

}  // namespace

void runParallel(size_t n, int threads, const std::function<void(size_t)>& task) {
  static ThreadPool pool;
  pool.run(n, threads, task);
}

}  // namespace hsr
