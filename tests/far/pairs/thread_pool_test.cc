#include "far/pairs/thread_pool.h"

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

}  // namespace
}  // namespace far
