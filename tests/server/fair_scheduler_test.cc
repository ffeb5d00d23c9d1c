#include "fair_scheduler.h"

#include <map>

#include "latency_stats.h"
#include <gtest/gtest.h>

namespace far::server {
namespace {

using Clock = std::chrono::steady_clock;

TEST(FairSchedulerTest, ServesSessionsRoundRobin) {
  FairScheduler<int> scheduler({.max_queued_per_session = 10, .max_queued_total = 100});
  const auto now = Clock::now();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(scheduler.Push(7, 700 + i, now).ok());
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(scheduler.Push(2, 200 + i, now).ok());
  ASSERT_TRUE(scheduler.Push(5, 500, now).ok());
  std::vector<int> order;
  while (auto job = scheduler.Pop()) order.push_back(job->second);
  EXPECT_EQ(order, (std::vector<int>{200, 500, 700, 201, 701, 202, 702}));
}

TEST(FairSchedulerTest, FloodingSessionGetsBusyAndOthersStillServed) {
  FairScheduler<int> scheduler({.max_queued_per_session = 4, .max_queued_total = 100});
  const auto now = Clock::now();
  int busy = 0;
  for (int i = 0; i < 100; ++i) {
    auto pushed = scheduler.Push(1, i, now);
    if (!pushed.ok()) {
      EXPECT_EQ(pushed.error().code, ErrorCode::kBusy);
      EXPECT_NE(pushed.error().message.find("pending"), std::string::npos);
      ++busy;
    }
  }
  EXPECT_EQ(busy, 96);
  ASSERT_TRUE(scheduler.Push(2, 1000, now).ok());
  // The quiet session is served second, not after the flood.
  EXPECT_EQ(scheduler.Pop()->first, 1);
  EXPECT_EQ(scheduler.Pop()->first, 2);
}

TEST(FairSchedulerTest, RateLimitRefillsOverTime) {
  FairScheduler<int> scheduler({.max_queued_per_session = 1000,
                                .max_queued_total = 1000,
                                .max_rate_per_session = 10,
                                .burst_per_session = 5});
  auto now = Clock::now();
  int accepted = 0;
  for (int i = 0; i < 20; ++i) accepted += scheduler.Push(1, i, now).ok();
  EXPECT_EQ(accepted, 5);
  now += std::chrono::milliseconds(500);  // 5 more tokens
  accepted = 0;
  for (int i = 0; i < 20; ++i) accepted += scheduler.Push(1, i, now).ok();
  EXPECT_EQ(accepted, 5);
}

TEST(FairSchedulerTest, TotalBoundHoldsAcrossSessions) {
  FairScheduler<int> scheduler({.max_queued_per_session = 4, .max_queued_total = 10});
  const auto now = Clock::now();
  int accepted = 0;
  for (int64_t s = 0; s < 10; ++s) {
    for (int i = 0; i < 4; ++i) accepted += scheduler.Push(s, i, now).ok();
  }
  EXPECT_EQ(accepted, 10);
  EXPECT_EQ(scheduler.size(), 10u);
  EXPECT_EQ(scheduler.RemoveSession(0).size(), 4u);
  EXPECT_EQ(scheduler.size(), 6u);
}

TEST(LatencyWindowTest, QuantilesOfRecentSamples) {
  LatencyWindow window(100);
  for (int i = 1; i <= 100; ++i) window.Add(i);
  EXPECT_DOUBLE_EQ(window.Quantile(0.5), 50.5);  // far::Quantile interpolates
  EXPECT_DOUBLE_EQ(window.Quantile(0.99), 99.01);
  EXPECT_DOUBLE_EQ(window.Quantile(1.0), 100);
  for (int i = 0; i < 100; ++i) window.Add(1000);  // the window forgets old samples
  EXPECT_DOUBLE_EQ(window.Quantile(0.5), 1000);
  EXPECT_EQ(window.count(), 200u);
}

}  // namespace
}  // namespace far::server
