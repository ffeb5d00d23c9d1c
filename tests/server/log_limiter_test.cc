#include "log_limiter.h"

#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

namespace far::server {
namespace {

using Clock = LogLimiter::Clock;
using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr uid_t kAlice = 1001, kBob = 1002;

// A limiter of 1 line/s, bursts of 3, a summary every 10 s, whose summaries land in `out`.
LogLimiter MakeLimiter(std::vector<LogLimiter::Summary>* out) {
  return LogLimiter({.lines_per_second = 1, .burst = 3, .summary_period = seconds(10)},
                    [out](const LogLimiter::Summary& s) { out->push_back(s); });
}

TEST(LogLimiterTest, AllowsABurstThenTheRateAndSummarizesWhatItHeldBack) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  int allowed = 0;
  for (int i = 0; i < 100; ++i) allowed += limiter.Allow(kAlice, "step_busy", t0);
  EXPECT_EQ(allowed, 3);
  // One more line a second after.
  EXPECT_TRUE(limiter.Allow(kAlice, "step_busy", t0 + seconds(1)));
  EXPECT_FALSE(limiter.Allow(kAlice, "step_busy", t0 + seconds(1)));
  EXPECT_TRUE(summaries.empty()) << "no summary before its period";
  // Ten seconds after the first line held back: one summary with all 98 of them.
  limiter.Flush(t0 + seconds(10));
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_EQ(summaries[0].uid, kAlice);
  EXPECT_EQ(summaries[0].kind, "step_busy");
  EXPECT_EQ(summaries[0].count, 98);
  EXPECT_DOUBLE_EQ(summaries[0].seconds, 10);
  // Said once: nothing more to say.
  limiter.Flush(t0 + seconds(20));
  EXPECT_EQ(summaries.size(), 1u);
}

TEST(LogLimiterTest, AFloodThatGoesOnIsSummarizedEveryPeriodWithoutAFlush) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  // 1000 lines a second for 25 s.
  int64_t allowed = 0, calls = 0;
  for (int ms = 0; ms < 25'000; ++ms, ++calls)
    allowed += limiter.Allow(kAlice, "open_refused", t0 + milliseconds(ms));
  EXPECT_EQ(allowed, 3 + 24);  // the burst, then one a second
  ASSERT_EQ(summaries.size(), 2u);
  EXPECT_NEAR(summaries[0].seconds, 10, 0.01);
  EXPECT_NEAR(summaries[1].seconds, 10, 0.01);
  limiter.Flush(t0 + seconds(40));
  ASSERT_EQ(summaries.size(), 3u);
  int64_t held = 0;
  for (const auto& s : summaries) held += s.count;
  EXPECT_EQ(held + allowed, calls) << "every line is either written or counted";
}

TEST(LogLimiterTest, UsersAndKindsHaveBucketsOfTheirOwn) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  for (int i = 0; i < 1000; ++i) limiter.Allow(kAlice, "step_busy", t0);
  // Alice's flood of one kind holds back neither Bob's lines nor her other kinds.
  EXPECT_TRUE(limiter.Allow(kBob, "step_busy", t0));
  EXPECT_TRUE(limiter.Allow(kAlice, "session_open", t0));
  EXPECT_TRUE(limiter.Allow(LogLimiter::kNoUser, "step_busy", t0));
  limiter.Flush(t0 + seconds(10));
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_EQ(summaries[0].uid, kAlice);
  EXPECT_EQ(summaries[0].count, 997);
}

TEST(LogLimiterTest, FlushAllSaysWhatIsHeldBackAtOnce) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  for (int i = 0; i < 5; ++i) limiter.Allow(kBob, "open_failed", t0);
  limiter.Flush(t0 + milliseconds(1500));
  EXPECT_TRUE(summaries.empty());
  limiter.Flush(t0 + milliseconds(1500), /*all=*/true);  // the daemon stops
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_EQ(summaries[0].count, 2);
  EXPECT_NEAR(summaries[0].seconds, 1.5, 1e-9);
}

TEST(LogLimiterTest, ForgetsPairsWhoseBucketRefilled) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  for (uid_t uid = 0; uid < 100; ++uid) limiter.Allow(uid, "session_open", t0);
  limiter.Allow(kAlice, "step_busy", t0);
  EXPECT_EQ(limiter.tracked(), 101u);
  // A burst of 3 at 1/s refills in 3 s: a pair last seen then has nothing to remember.
  limiter.Flush(t0 + seconds(2));
  EXPECT_EQ(limiter.tracked(), 101u);
  limiter.Flush(t0 + seconds(3));
  EXPECT_EQ(limiter.tracked(), 0u);
  EXPECT_TRUE(summaries.empty());
}

TEST(LogLimiterTest, FlushDoesItsWorkAtMostOnceASecond) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  const auto t0 = Clock::now();
  for (int i = 0; i < 5; ++i) limiter.Allow(kAlice, "step_busy", t0);
  limiter.Flush(t0 + milliseconds(9'500));  // not due: the next look is a second later
  limiter.Flush(t0 + milliseconds(10'000));
  EXPECT_TRUE(summaries.empty());
  limiter.Flush(t0 + milliseconds(10'500));
  EXPECT_EQ(summaries.size(), 1u);
}

TEST(LogLimiterTest, EveryLineFromManyThreadsIsWrittenOrCounted) {
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter = MakeLimiter(&summaries);
  constexpr int kThreads = 4, kLines = 5000;
  std::vector<int> allowed(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kLines; ++i) allowed[t] += limiter.Allow(kAlice, "step_busy");
    });
  }
  for (auto& thread : threads) thread.join();
  limiter.Flush(Clock::now(), /*all=*/true);
  int64_t total = 0;
  for (int a : allowed) total += a;
  for (const auto& s : summaries) total += s.count;
  EXPECT_EQ(total, kThreads * kLines);
}

TEST(LogLimiterTest, TheSummaryLineNamesKindUserCountAndSeconds) {
  std::ostringstream text;
  auto logger = std::make_shared<spdlog::logger>(
      "test", std::make_shared<spdlog::sinks::ostream_sink_mt>(text));
  logger->set_pattern("%v");
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(logger);
  LogLimiter::LogSummary({kAlice, "step_busy", 41872, 10.2});
  LogLimiter::LogSummary({LogLimiter::kNoUser, "handler_exception", 3, 1.5});
  spdlog::set_default_logger(previous);
  EXPECT_EQ(text.str(),
            "event=log_suppressed kind=step_busy user=1001 count=41872 seconds=10\n"
            "event=log_suppressed kind=handler_exception user=unknown count=3 seconds=2\n");
}

}  // namespace
}  // namespace far::server
