#include "rate_limiter.h"

#include "setup_allowance.h"
#include <gtest/gtest.h>

namespace far::server {
namespace {

using Clock = RateLimiter::Clock;

TEST(RateLimiterTest, AllowsABurstThenTheSustainedRate) {
  RateLimiter limiter(/*rate=*/10, /*burst=*/3);
  const auto t0 = Clock::now();
  EXPECT_TRUE(limiter.Allow(t0));
  EXPECT_TRUE(limiter.Allow(t0));
  EXPECT_TRUE(limiter.Allow(t0));
  EXPECT_FALSE(limiter.Allow(t0));  // the burst is spent
  // 100 ms later one more token (10 per second) has come back, no more.
  EXPECT_TRUE(limiter.Allow(t0 + std::chrono::milliseconds(100)));
  EXPECT_FALSE(limiter.Allow(t0 + std::chrono::milliseconds(100)));
  // A long pause refills to the burst, not beyond.
  const auto later = t0 + std::chrono::seconds(60);
  int allowed = 0;
  while (limiter.Allow(later)) ++allowed;
  EXPECT_EQ(allowed, 3);
}

TEST(RateLimiterTest, TakesPartOfAnAmountWhenThatIsAllItHolds) {
  RateLimiter bucket(/*rate=*/100, /*burst=*/1000);
  const auto t0 = Clock::now();
  EXPECT_DOUBLE_EQ(bucket.TakeUpTo(600, t0), 600);
  EXPECT_DOUBLE_EQ(bucket.TakeUpTo(600, t0), 400);  // what was left
  EXPECT_DOUBLE_EQ(bucket.TakeUpTo(1, t0), 0);
  EXPECT_DOUBLE_EQ(bucket.Available(t0 + std::chrono::seconds(2)), 200);
  EXPECT_DOUBLE_EQ(bucket.TakeUpTo(-5, t0 + std::chrono::seconds(2)), 0);  // nothing given back
  EXPECT_DOUBLE_EQ(bucket.Available(t0 + std::chrono::seconds(60)), 1000);
  // A time earlier than one already seen refills nothing and takes nothing away.
  EXPECT_DOUBLE_EQ(bucket.Available(t0), 1000);
}

TEST(SetupAllowanceTest, EachUserHasABurstRefilledAtATenthOfItPerSecond) {
  SetupAllowance allowance(/*burst_ms=*/1000);
  const auto t0 = Clock::now();
  EXPECT_DOUBLE_EQ(allowance.TakeUpTo(1000, 700, t0), 700);
  EXPECT_DOUBLE_EQ(allowance.TakeUpTo(1000, 700, t0), 300);
  // Another user's bucket is its own.
  EXPECT_DOUBLE_EQ(allowance.Available(1001, t0), 1000);
  // 100 ms per second come back.
  EXPECT_DOUBLE_EQ(allowance.Available(1000, t0 + std::chrono::milliseconds(2500)), 250);
  EXPECT_DOUBLE_EQ(allowance.TakeUpTo(1000, 1e9, t0 + std::chrono::seconds(30)), 1000);
}

TEST(SetupAllowanceTest, ZeroCoversNothing) {
  SetupAllowance allowance(0);
  const auto t0 = Clock::now();
  EXPECT_DOUBLE_EQ(allowance.TakeUpTo(1000, 50, t0), 0);
  EXPECT_DOUBLE_EQ(allowance.Available(1000, t0 + std::chrono::hours(1)), 0);
}

}  // namespace
}  // namespace far::server
