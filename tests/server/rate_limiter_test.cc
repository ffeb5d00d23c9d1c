#include "rate_limiter.h"

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

}  // namespace
}  // namespace far::server
