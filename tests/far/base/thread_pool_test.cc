#include "far/base/thread_pool.h"

#include <sched.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace far {
namespace {

TEST(ThreadPoolTest, VisitsEveryIndexExactlyOnce) {
  ThreadPool pool(4);
  for (size_t count : {0u, 1u, 7u, 1000u, 100003u}) {
    std::vector<std::atomic<int>> visits(count);
    pool.ParallelFor(count, 64, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) visits[i].fetch_add(1);
    });
    for (size_t i = 0; i < count; ++i) ASSERT_EQ(visits[i].load(), 1) << "index " << i;
  }
}

TEST(ThreadPoolTest, RunsManyLoopsInSequence) {
  ThreadPool pool(3);
  std::atomic<long> sum = 0;
  for (int round = 0; round < 200; ++round) {
    pool.ParallelFor(100, 7, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) sum += static_cast<long>(i);
    });
  }
  EXPECT_EQ(sum.load(), 200L * 4950L);
}

// A loop returns only when every chunk has run, also when a worker wakes after the caller has
// taken every chunk (the caller does not wait for such a worker; it must not run anything of a
// loop that has returned). Tiny loops, some after an idle gap that lets the workers sleep;
// each loop's counts live on the stack and die when it returns, which the sanitizer builds
// would catch a late chunk writing to.
TEST(ThreadPoolTest, TinyLoopsFinishBeforeTheyReturn) {
  ThreadPool pool(3);
  for (int round = 0; round < 20000; ++round) {
    if (round % 1000 == 999) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const size_t count = 1 + round % 3;
    std::atomic<int> visits[3] = {0, 0, 0};
    pool.ParallelFor(count, 1, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) visits[i].fetch_add(1);
    });
    for (size_t i = 0; i < 3; ++i)
      ASSERT_EQ(visits[i].load(), i < count ? 1 : 0) << "round " << round << ", index " << i;
  }
}

// The threads that ran chunks of one loop of `count` indices (each chunk sleeps a little, so
// that every thread allowed to take part gets some), and the scheduling policy of each chunk
// a worker ran.
std::set<std::thread::id> ThreadsOfOneLoop(ThreadPool& pool, size_t count,
                                           std::vector<int>* policies = nullptr) {
  const std::thread::id caller = std::this_thread::get_id();
  std::mutex mutex;
  std::set<std::thread::id> threads;
  std::vector<std::atomic<int>> visits(count);
  pool.ParallelFor(count, 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) visits[i].fetch_add(1);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::lock_guard lock(mutex);
    threads.insert(std::this_thread::get_id());
    if (policies != nullptr && std::this_thread::get_id() != caller)
      policies->push_back(sched_getscheduler(0));
  });
  for (size_t i = 0; i < count; ++i) EXPECT_EQ(visits[i].load(), 1) << "index " << i;
  return threads;
}

TEST(ThreadPoolTest, BackgroundLoopsUseAtMostTheirThreadsAndIdlePriority) {
  ThreadPool pool(4);
  EXPECT_GT(ThreadsOfOneLoop(pool, 200).size(), 1u);  // the workers help
  pool.SetBackground(2);
  std::vector<int> policies;
  for (int round = 0; round < 5; ++round) {
    const auto threads = ThreadsOfOneLoop(pool, 200, &policies);
    EXPECT_LE(threads.size(), 2u);
    EXPECT_TRUE(threads.count(std::this_thread::get_id()));
  }
  // The worker that took part lowered itself; the calling thread is the caller's to lower.
  ASSERT_FALSE(policies.empty());
  for (int policy : policies) EXPECT_EQ(policy, SCHED_IDLE);
  EXPECT_NE(sched_getscheduler(0), SCHED_IDLE);
  pool.SetBackground(1);
  EXPECT_EQ(ThreadsOfOneLoop(pool, 50), std::set<std::thread::id>{std::this_thread::get_id()});
}

// A daemon's session whose share of the cores is one thread runs its loops alone, and gets its
// workers back when its share grows (Pipeline::SetCpuShare).
TEST(ThreadPoolTest, LoopsUseAtMostTheShareAndGetTheirThreadsBackWhenItGrows) {
  ThreadPool pool(4);
  pool.SetShare(1);
  EXPECT_EQ(ThreadsOfOneLoop(pool, 50), std::set<std::thread::id>{std::this_thread::get_id()});
  pool.SetShare(0);  // at least one thread
  EXPECT_EQ(ThreadsOfOneLoop(pool, 50), std::set<std::thread::id>{std::this_thread::get_id()});
  pool.SetShare(2);
  for (int round = 0; round < 5; ++round) EXPECT_LE(ThreadsOfOneLoop(pool, 200).size(), 2u);
  pool.SetShare(5);
  EXPECT_GT(ThreadsOfOneLoop(pool, 200).size(), 2u);
}

// A worker queued on the caller's CPU waits while the caller runs the loop (on a VM, 32-42% of
// the loops after an idle gap ran on one thread): the pool keeps its workers off that CPU.
TEST(ThreadPoolTest, WorkersRunOffTheCallersCpu) {
  cpu_set_t saved;
  ASSERT_EQ(sched_getaffinity(0, sizeof saved, &saved), 0);
  if (CPU_COUNT(&saved) < 2) GTEST_SKIP() << "one CPU allowed";
  ThreadPool pool(3);
  for (int round = 0; round < 3; ++round) {
    // Pin the caller to one of its CPUs, a different one each round.
    int caller_cpu = -1;
    for (int cpu = 0, seen = 0; cpu < CPU_SETSIZE && caller_cpu < 0; ++cpu) {
      if (CPU_ISSET(cpu, &saved) && seen++ == round % CPU_COUNT(&saved)) caller_cpu = cpu;
    }
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(caller_cpu, &one);
    ASSERT_EQ(sched_setaffinity(0, sizeof one, &one), 0);
    const std::thread::id caller = std::this_thread::get_id();
    std::atomic<int> worker_chunks = 0, on_caller_cpu = 0, allowed_caller_cpu = 0;
    pool.ParallelFor(100, 1, [&](size_t, size_t) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      if (std::this_thread::get_id() == caller) return;
      ++worker_chunks;
      if (sched_getcpu() == caller_cpu) ++on_caller_cpu;
      cpu_set_t mask;
      if (sched_getaffinity(0, sizeof mask, &mask) == 0 && CPU_ISSET(caller_cpu, &mask))
        ++allowed_caller_cpu;
    });
    ASSERT_EQ(sched_setaffinity(0, sizeof saved, &saved), 0);
    EXPECT_GT(worker_chunks.load(), 0) << "round " << round;
    EXPECT_EQ(on_caller_cpu.load(), 0) << "round " << round;
    EXPECT_EQ(allowed_caller_cpu.load(), 0) << "round " << round;
  }
}

}  // namespace
}  // namespace far
