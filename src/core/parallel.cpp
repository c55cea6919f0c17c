// The persistent thread pool behind parallelFor (see parallel.hpp). Between jobs a worker first
// spins for a while (kPoolSpin), watching for the next job, then sleeps on a condition variable;
// the caller likewise spins a while for the workers to finish before it sleeps. A frame runs
// several jobs back to back (vertices, set-up and binning, tiles, resolve), and waking a
// sleeping thread costs tens of microseconds in a virtual machine. Worker w always takes part
// w + 1 of a job (WorkQueue), and only when the job has that many parts.
#include "core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

namespace hsr {
namespace {

thread_local size_t tPart = 0;  // currentPart(): set once by each pool worker

// Spins until ready() or kPoolSpin has passed; returns ready().
template <class Ready>
bool spinUntil(Ready&& ready) {
  const auto until = std::chrono::steady_clock::now() + kPoolSpin;
  for (;;) {
    for (int i = 0; i < 64; ++i) {
      if (ready()) return true;
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#elif defined(__aarch64__)
      asm volatile("yield");
#endif
    }
    if (std::chrono::steady_clock::now() >= until) return ready();
  }
}

class ThreadPool {
 public:
  ThreadPool() {
    const int workers = std::max(1, resolveThreads(0) - 1);
    for (int i = 0; i < workers; ++i) threads_.emplace_back([this, i] { work(size_t(i)); });
  }
  ~ThreadPool() {
    {
      std::lock_guard lock(m_);
      stop_.store(true);
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
      admit_.store(int(std::min<size_t>({size_t(threads - 1), threads_.size(), n - 1})), std::memory_order_relaxed);
      queue_.reset(n, size_t(admit_.load(std::memory_order_relaxed)) + 1);
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    drain(0);
    {
      std::lock_guard lock(m_);
      // No worker may join after this: task_ is about to go out of scope.
      admit_.store(0, std::memory_order_relaxed);
    }
    spinUntil([&] { return active_.load(std::memory_order_acquire) == 0; });
    std::unique_lock lock(m_);
    done_.wait(lock, [&] { return active_.load(std::memory_order_relaxed) == 0; });
    task_ = nullptr;
  }

 private:
  void drain(size_t part) {
    for (size_t i; (i = queue_.next(part)) < queue_.size();) (*task_)(i);
  }
  void work(size_t index) {
    tPart = index + 1;
    uint64_t seen = 0;
    // A job this worker takes part in (read again under the lock before joining it).
    auto called = [&] {
      return stop_.load(std::memory_order_relaxed) || (generation_.load(std::memory_order_acquire) != seen &&
                                                       index < size_t(admit_.load(std::memory_order_relaxed)));
    };
    for (;;) {
      const bool ready = spinUntil(called);
      std::unique_lock lock(m_);
      if (!ready) wake_.wait(lock, called);
      else if (!called()) continue;  // the job ended before this worker could join: spin again
      if (stop_) return;
      seen = generation_.load(std::memory_order_relaxed);
      active_.fetch_add(1, std::memory_order_relaxed);
      lock.unlock();
      drain(tPart);
      lock.lock();
      if (active_.fetch_sub(1, std::memory_order_release) == 1) done_.notify_all();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex jobMutex_;  // one job at a time
  std::mutex m_;
  std::condition_variable wake_, done_;
  const std::function<void(size_t)>* task_ = nullptr;
  WorkQueue queue_;
  // Written under m_; atomic so that a spinning thread may read them without it.
  std::atomic<int> admit_{0};  // workers [0, admit_) take part in the current job
  std::atomic<int> active_{0};
  std::atomic<uint64_t> generation_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace

void WorkQueue::setParts(size_t parts) {
  if (parts > capacity_) {
    lists_.reset(new List[parts]);
    capacity_ = parts;
  }
  parts_ = parts;
}

void WorkQueue::reset(size_t n, size_t parts) {
  setParts(parts);
  order_.clear();
  n_ = n;
  const size_t size = (n + parts - 1) / parts;
  for (size_t p = 0; p < parts; ++p) {
    lists_[p].next.store(std::min(n, p * size), std::memory_order_relaxed);
    lists_[p].end = std::min(n, (p + 1) * size);
  }
}

void WorkQueue::reset(const uint32_t* order, size_t n, const size_t* bounds, size_t parts) {
  setParts(parts);
  order_.assign(order, order + n);
  n_ = n;
  for (size_t p = 0; p < parts; ++p) {
    lists_[p].next.store(bounds[p], std::memory_order_relaxed);
    lists_[p].end = bounds[p + 1];
  }
}

size_t currentPart() { return tPart; }

void runParallel(size_t n, int threads, const std::function<void(size_t)>& task) {
  static ThreadPool pool;
  pool.run(n, threads, task);
}

}  // namespace hsr
