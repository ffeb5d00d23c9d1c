#include "far/pairs/thread_pool.h"

#include <sys/resource.h>

#include <algorithm>

namespace far {

ThreadPool::ThreadPool(int num_threads) {
  if (num_threads <= 0)
    num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // The calling thread works too, so start one worker fewer than asked.
  for (int i = 1; i < num_threads; ++i) workers_.emplace_back([this] { WorkerLoop(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (auto& worker : workers_) worker.join();
}

void ThreadPool::ParallelFor(size_t count, size_t grain,
                             const std::function<void(size_t, size_t)>& body) {
  if (count == 0) return;
  grain = std::max<size_t>(grain, 1);
  // Small loops are not worth waking anyone.
  if (workers_.empty() || count <= grain) {
    body(0, count);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    body_ = &body;
    count_ = count;
    grain_ = grain;
    next_ = 0;
    active_ = workers_.size() + 1;
    ++generation_;
  }
  wake_.notify_all();
  RunChunks();
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return active_ == 0; });
  body_ = nullptr;
}

void ThreadPool::RunChunks() {
  // Take chunks until none are left, then report this thread finished.
  for (;;) {
    size_t begin;
    {
      std::lock_guard lock(mutex_);
      begin = next_;
      next_ = std::min(count_, next_ + grain_);
    }
    if (begin >= count_) break;
    (*body_)(begin, std::min(count_, begin + grain_));
  }
  std::lock_guard lock(mutex_);
  if (--active_ == 0) done_.notify_all();
}

void ThreadPool::WorkerLoop() {
  uint64_t seen = 0;
  int applied_nice = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    // On Linux, PRIO_PROCESS with who = 0 sets the calling thread's nice value only.
    if (const int nice = nice_.load(); nice != applied_nice) {
      setpriority(PRIO_PROCESS, 0, nice);
      applied_nice = nice;
    }
    RunChunks();
  }
}

void ThreadPool::SetNice(int nice) { nice_ = nice; }

}  // namespace far
