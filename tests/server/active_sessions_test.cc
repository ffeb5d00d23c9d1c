// ActiveSessions: the sessions that stepped within the last second, each counted once.
#include "active_sessions.h"

#include <gtest/gtest.h>

namespace far::server {
namespace {

using std::chrono::milliseconds;

TEST(ActiveSessionsTest, CountsTheSessionsThatSteppedWithinTheWindow) {
  ActiveSessions active;
  const auto t0 = ActiveSessions::Clock::time_point{} + std::chrono::hours(1);
  EXPECT_EQ(active.Stepping(1, t0), 1);
  EXPECT_EQ(active.Stepping(1, t0 + milliseconds(10)), 1) << "a session counts once";
  EXPECT_EQ(active.Stepping(2, t0 + milliseconds(20)), 2);
  EXPECT_EQ(active.Stepping(3, t0 + milliseconds(900)), 3);
  // Session 1 last stepped 1.2 s before: no longer sharing the cores.
  EXPECT_EQ(active.Stepping(2, t0 + milliseconds(1210)), 2);
  EXPECT_EQ(active.Stepping(3, t0 + milliseconds(3000)), 1);
}

}  // namespace
}  // namespace far::server
