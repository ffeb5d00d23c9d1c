#include "far/pairs/thread_pool.h"

#include <atomic>
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

}  // namespace
}  // namespace far
