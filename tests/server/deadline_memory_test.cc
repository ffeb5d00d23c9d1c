// DeadlineMemory: a step that ran into the daemon's deadline on its own time makes the same
// request on a scene at least as large fail at once, until the recheck time; anything else
// runs. A step that waited (in its queue, behind another session's GL work) for more than the
// deadline's slack is not blamed for the deadline.
#include "deadline_memory.h"

#include <gtest/gtest.h>

namespace far::server {
namespace {

using namespace std::chrono_literals;
using Clock = DeadlineMemory::Clock;
using StepEnd = DeadlineMemory::StepEnd;

StepRequest Request(Method method, Output output = Output::kContacts) {
  StepRequest request;
  request.method = method;
  request.output = output;
  return request;
}

// A step that ran into the deadline after running `ran` on its own.
StepEnd HitDeadline(std::chrono::milliseconds ran) {
  return {true, ran, "step stopped at its deadline (during exact)"};
}
const StepEnd kFinished{false, 10ms, ""};

TEST(DeadlineMemoryTest, RefusesTheSameRequestOnASceneNoSmallerUntilTheRecheck) {
  DeadlineMemory memory(5s, 6);
  const auto t0 = Clock::now();
  const StepRequest heavy = Request(Method::kAabb);
  EXPECT_TRUE(memory.Check(heavy, 1000, t0).ok());  // nothing known yet
  memory.Record(heavy, 1000, HitDeadline(5s), t0);

  const auto refused = memory.Check(heavy, 1000, t0 + 1s);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(refused.error().message.find("ran into the daemon's step deadline"), std::string::npos)
      << refused.error().message;
  EXPECT_NE(refused.error().message.find("during exact"), std::string::npos);
  EXPECT_FALSE(memory.Check(heavy, 2000, t0 + 1s).ok());  // a larger scene too

  EXPECT_TRUE(memory.Check(heavy, 999, t0 + 1s).ok());                   // a smaller scene
  EXPECT_TRUE(memory.Check(Request(Method::kBvh), 1000, t0 + 1s).ok());  // another method
  StepRequest nearer = heavy;
  nearer.distance = 0.5;
  EXPECT_TRUE(memory.Check(nearer, 1000, t0 + 1s).ok());  // another distance
  EXPECT_TRUE(memory.Check(heavy, 1000, t0 + 30s).ok());  // time to measure again (6 x 5 s)
}

TEST(DeadlineMemoryTest, AStepOfTheSameRequestThatFitsForgetsIt) {
  DeadlineMemory memory(5s, 6);
  const auto t0 = Clock::now();
  const StepRequest heavy = Request(Method::kAabb);
  memory.Record(heavy, 1000, HitDeadline(5s), t0);
  memory.Record(Request(Method::kBvh), 1000, kFinished, t0 + 1s);  // another request: no change
  EXPECT_FALSE(memory.Check(heavy, 1000, t0 + 2s).ok());
  memory.Record(heavy, 1000, kFinished, t0 + 31s);  // the recheck finished in time
  EXPECT_TRUE(memory.Check(heavy, 1000, t0 + 32s).ok());
}

TEST(DeadlineMemoryTest, AStepThatRanIntoTheDeadlineAfterWaitingIsNotBlamed) {
  // Issue 41: a light step (960 triangles) that waited behind another session's 223-s step until
  // its own deadline had nearly passed ran for a moment, stopped at the deadline, and its
  // request was refused at once 41 times for 6 deadlines.
  DeadlineMemory memory(60s, 6);
  const auto t0 = Clock::now();
  const StepRequest light = Request(Method::kFar);
  memory.Record(light, 960, HitDeadline(40ms), t0);
  EXPECT_TRUE(memory.Check(light, 960, t0 + 1s).ok());
  // Waited for more than the slack (3 s of 60: 5%): still not blamed.
  memory.Record(light, 960, HitDeadline(56'900ms), t0 + 60s);
  EXPECT_TRUE(memory.Check(light, 960, t0 + 61s).ok());
  // Ran for the whole deadline but its slack: blamed.
  memory.Record(light, 960, HitDeadline(57s), t0 + 120s);
  EXPECT_FALSE(memory.Check(light, 960, t0 + 121s).ok());
}

TEST(DeadlineMemoryTest, AStepThatWaitedNeitherBlamesNorClearsARememberedOne) {
  DeadlineMemory memory(5s, 6);
  const auto t0 = Clock::now();
  const StepRequest heavy = Request(Method::kAabb);
  memory.Record(heavy, 1000, HitDeadline(5s), t0);
  // A step of it that waited in the queue and stopped at the deadline shows nothing either way.
  memory.Record(heavy, 1000, HitDeadline(200ms), t0 + 6s);
  EXPECT_FALSE(memory.Check(heavy, 1000, t0 + 7s).ok());
  EXPECT_TRUE(memory.Check(heavy, 1000, t0 + 30s).ok());  // the recheck is still due at 30 s
}

TEST(DeadlineMemoryTest, TheSlackIsOneSecondOrFivePercentOfTheDeadline) {
  EXPECT_EQ(DeadlineMemory(60s, 6).blame_after(), 57s);
  EXPECT_EQ(DeadlineMemory(5s, 6).blame_after(), 4s);
  EXPECT_EQ(DeadlineMemory(500ms, 6).blame_after(), -500ms);  // any step is blamed
}

}  // namespace
}  // namespace far::server
