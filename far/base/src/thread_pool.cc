#include "far/base/thread_pool.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>

#include <algorithm>

namespace far {

ThreadPool::ThreadPool(int num_threads) {
  if (num_threads <= 0)
    num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // The calling thread works too, so start one worker fewer than asked.
  taking_part_ = static_cast<size_t>(num_threads - 1);
  CPU_ZERO(&worker_cpus_);
  if (sched_getaffinity(0, sizeof worker_cpus_, &worker_cpus_) != 0) CPU_ZERO(&worker_cpus_);
  for (int i = 1; i < num_threads; ++i) {
    workers_.emplace_back([this, i] { WorkerLoop(static_cast<size_t>(i - 1)); });
  }
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
  const size_t helpers = std::min({workers_.size(), taking_part_.load(), share_helpers_.load()});
  if (helpers == 0 || count <= grain) {
    body(0, count);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    body_ = &body;
    count_ = count;
    grain_ = grain;
    next_ = 0;
    active_ = 1;  // this thread; each worker that joins while chunks are left adds itself
    helpers_ = helpers;
    ++generation_;
  }
  KeepWorkersOffThisCpu();
  wake_.notify_all();
  RunChunks();
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return active_ == 0; });
  body_ = nullptr;
}

// Why: a worker woken while the caller runs may be queued on the caller's own CPU, and wait
// there while the caller does the whole loop. On a 2-vCPU KVM guest that happened in 32-42% of
// the loops after an idle gap of 1-6 ms (far_thread_pool_benchmark; probably because the
// scheduler does not count a vCPU the host has descheduled as idle), and those loops ran on
// one thread. Keeping the workers off the caller's CPU makes the wake-up put them elsewhere.
// The masks change only when the caller has moved.
void ThreadPool::KeepWorkersOffThisCpu() {
  const int cpu = sched_getcpu();
  if (cpu < 0 || cpu == excluded_cpu_) return;
  cpu_set_t allowed = worker_cpus_;
  CPU_CLR(cpu, &allowed);
  if (CPU_COUNT(&allowed) == 0) return;
  for (std::thread& worker : workers_) {
    pthread_setaffinity_np(worker.native_handle(), sizeof allowed, &allowed);
  }
  excluded_cpu_ = cpu;
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

void ThreadPool::WorkerLoop(size_t index) {
  uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      if (index >= helpers_) continue;  // not taking part in this loop
      // A worker that wakes after every chunk was taken stays out, and the caller does not wait
      // for it: a small loop the caller finished alone does not wait for a wake-up (on the 2-vCPU
      // VM, 20-40 us after an idle gap).
      if (next_ >= count_) continue;
      ++active_;
    }
    if (background_.load()) MoveCallingThreadToBackground();
    RunChunks();
  }
}

void ThreadPool::SetBackground(int max_threads) {
  taking_part_ = static_cast<size_t>(std::max(1, max_threads) - 1);
  background_ = true;
}

void ThreadPool::SetShare(int max_threads) {
  share_helpers_ = static_cast<size_t>(std::max(1, max_threads) - 1);
}

void ThreadPool::MoveCallingThreadToBackground() {
  thread_local bool moved = false;
  if (moved) return;
  // On Linux, who = 0 and pid 0 name the calling thread only. SCHED_IDLE: a normal thread that
  // wakes takes the core at once; nice alone left it waiting for this thread's time slice.
  setpriority(PRIO_PROCESS, 0, kBackgroundNice);
  sched_param param{};
  sched_setscheduler(0, SCHED_IDLE, &param);
  moved = true;
}

namespace {
double ClockMs(clockid_t clock) {
  timespec t{};
  if (clock_gettime(clock, &t) != 0) return 0;
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}
}  // namespace

double ThreadPool::WorkersCpuMs() const {
  double ms = 0;
  for (const std::thread& worker : workers_) {
    clockid_t clock;
    if (pthread_getcpuclockid(const_cast<std::thread&>(worker).native_handle(), &clock) == 0)
      ms += ClockMs(clock);
  }
  return ms;
}

double ThreadPool::CallingThreadCpuMs() { return ClockMs(CLOCK_THREAD_CPUTIME_ID); }

}  // namespace far
