#pragma once

#include <sched.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
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
  /// The workers run on the CPUs the pool's constructor was allowed, except the one the caller
  /// calls from (when there is another), so that none waits for a core the caller holds.
  void ParallelFor(size_t count, size_t grain, const std::function<void(size_t, size_t)>& body);

  /// Makes the pool background work from its next loop on: each ParallelFor runs on at most
  /// `max_threads` threads (the calling thread and max_threads - 1 workers; at least 1), and
  /// the workers that take part run at nice 10 under SCHED_IDLE (Linux): they get a core only
  /// when no normal thread wants it, and give it up at once when one wakes. A daemon does this
  /// to a session whose steps are heavy, so that light sessions keep their latency (what nice
  /// alone did not do: bench/RESULTS.md). One way: an unprivileged process cannot undo it.
  void SetBackground(int max_threads);

  /// Runs each ParallelFor from the next one on on at most `max_threads` threads (the caller
  /// and max_threads - 1 workers; at least 1), until called again: the caller's share of cores
  /// it shares with others. Waking workers for a share of less than two cores only adds
  /// context switches to the cores' load (8 sessions stepping 1K triangles on 2 cores: 4,350
  /// steps/s with each session's loops on 2 threads, 5,940 on 1; bench/RESULTS.md). A lower
  /// SetBackground limit stays.
  void SetShare(int max_threads);

  /// CPU time the workers have used since they started, all together (ms; Linux thread CPU
  /// clocks, 0 elsewhere). With the caller's own thread CPU time, what a loop cost in CPU.
  double WorkersCpuMs() const;
  /// CPU time the calling thread has used since it started (ms).
  static double CallingThreadCpuMs();

  /// The nice value of background threads.
  static constexpr int kBackgroundNice = 10;
  /// Moves the calling thread to the background (nice kBackgroundNice under SCHED_IDLE, Linux),
  /// once per thread (later calls return at once): what SetBackground does to the workers, for
  /// another thread working on the same heavy job. One way, as SetBackground.
  static void MoveCallingThreadToBackground();

 private:
  void WorkerLoop(size_t index);
  void RunChunks();
  // Restricts the workers to worker_cpus_ but the CPU the caller runs on (Linux).
  void KeepWorkersOffThisCpu();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(size_t, size_t)>* body_ = nullptr;
  size_t count_ = 0, grain_ = 1, next_ = 0, active_ = 0;
  size_t helpers_ = 0;  // workers that take part in the current loop (index < helpers_)
  uint64_t generation_ = 0;
  bool stopping_ = false;
  cpu_set_t worker_cpus_;  // the CPUs the constructing thread was allowed (empty: unknown)
  int excluded_cpu_ = -1;  // the CPU the workers are kept off (-1: none yet)
  // Workers with an index below this take part in a loop; and whether they go to the background.
  std::atomic<size_t> taking_part_;
  std::atomic<size_t> share_helpers_{SIZE_MAX};  // SetShare: workers a loop may wake
  std::atomic<bool> background_{false};
};

}  // namespace far
