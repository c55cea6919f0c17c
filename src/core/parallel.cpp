// The persistent thread pool behind parallelFor (see parallel.hpp). Workers sleep on a
// condition variable between jobs; a job hands out indices through an atomic counter.
#include "core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <vector>

namespace hsr {
namespace {

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
      next_ = 0;
      end_ = n;
      admit_ = int(std::min<size_t>({size_t(threads - 1), threads_.size(), n - 1}));
      joined_ = 0;
      ++generation_;
    }
    wake_.notify_all();
    drain();
    std::unique_lock lock(m_);
    admit_ = joined_;  // no worker may join after this: task_ is about to go out of scope
    done_.wait(lock, [&] { return active_ == 0; });
    task_ = nullptr;
  }

 private:
  void drain() {
    for (size_t i; (i = next_.fetch_add(1)) < end_;) (*task_)(i);
  }
  void work() {
    uint64_t seen = 0;
    std::unique_lock lock(m_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || (generation_ != seen && joined_ < admit_); });
      if (stop_) return;
      seen = generation_;
      ++joined_;
      ++active_;
      lock.unlock();
      drain();
      lock.lock();
      if (--active_ == 0) done_.notify_all();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex jobMutex_;  // one job at a time
  std::mutex m_;
  std::condition_variable wake_, done_;
  const std::function<void(size_t)>* task_ = nullptr;
  std::atomic<size_t> next_{0};
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
