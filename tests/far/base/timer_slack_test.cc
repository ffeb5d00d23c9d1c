// ScopedTimerSlack: the thread's slack is lowered in scope and restored after, on this thread
// only.

#include "far/base/timer_slack.h"

#include <future>
#include <thread>

#include <gtest/gtest.h>

namespace far {
namespace {

TEST(TimerSlackTest, IsLoweredInScopeAndRestoredAfter) {
  const unsigned long before = ScopedTimerSlack::Current();
#if !defined(__linux__)
  GTEST_SKIP() << "timer slack is Linux's";
#endif
  ASSERT_GT(before, 1000u) << "a thread starts with the default slack (50 us)";
  {
    ScopedTimerSlack slack(1000);
    EXPECT_EQ(ScopedTimerSlack::Current(), 1000u);
    {
      ScopedTimerSlack nested(5000);
      EXPECT_EQ(ScopedTimerSlack::Current(), 5000u);
    }
    EXPECT_EQ(ScopedTimerSlack::Current(), 1000u);
  }
  EXPECT_EQ(ScopedTimerSlack::Current(), before);
}

TEST(TimerSlackTest, AThreadThatRunsAlreadyKeepsItsOwn) {
#if !defined(__linux__)
  GTEST_SKIP() << "timer slack is Linux's";
#endif
  const unsigned long before = ScopedTimerSlack::Current();
  std::promise<void> lowered;
  unsigned long seen = 0;
  std::thread other([&, wait = lowered.get_future()] {
    wait.wait();
    seen = ScopedTimerSlack::Current();
  });
  {
    ScopedTimerSlack slack(1000);
    lowered.set_value();
    other.join();
  }
  EXPECT_EQ(seen, before) << "the slack is the calling thread's, not the process's";
}

}  // namespace
}  // namespace far
