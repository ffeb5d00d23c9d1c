#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace far {

/// A fixed set of worker threads that runs index-parallel loops. Used for the exact tests.
/// Thread safety: ParallelFor may be called from one thread at a time.
class ThreadPool {
 public:
  /// Starts `num_threads` workers (0 = std::thread::hardware_concurrency()).
  explicit ThreadPool(int num_threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Threads that run a ParallelFor: the workers plus the calling thread.
  int num_threads() const { return static_cast<int>(workers_.size()) + 1; }

  /// Runs body(begin, end) over [0, count) split into chunks of at most `grain` indices, on the
  /// workers and the calling thread; returns when all chunks are done. `body` must not throw.
  void ParallelFor(size_t count, size_t grain, const std::function<void(size_t, size_t)>& body);

  /// Runs the workers at this nice value (Linux; from their next loop on). A daemon lowers the
  /// priority of a session whose steps are heavy, so that light sessions stay responsive.
  /// An unprivileged process can raise a nice value but not lower it again.
  void SetNice(int nice);

 private:
  void WorkerLoop();
  void RunChunks();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(size_t, size_t)>* body_ = nullptr;
  size_t count_ = 0, grain_ = 1, next_ = 0, active_ = 0;
  uint64_t generation_ = 0;
  bool stopping_ = false;
  std::atomic<int> nice_{0};
};

}  // namespace far
