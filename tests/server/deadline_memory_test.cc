// DeadlineMemory: a step that ran into the daemon's deadline makes the same request on a scene
// at least as large fail at once, until the recheck time; anything else runs.
#include "deadline_memory.h"

#include <gtest/gtest.h>

namespace far::server {
namespace {

using namespace std::chrono_literals;
using Clock = DeadlineMemory::Clock;

StepRequest Request(Method method, Output output = Output::kContacts) {
  StepRequest request;
  request.method = method;
  request.output = output;
  return request;
}

TEST(DeadlineMemoryTest, RefusesTheSameRequestOnASceneNoSmallerUntilTheRecheck) {
  DeadlineMemory memory(30s);
  const auto t0 = Clock::now();
  const StepRequest heavy = Request(Method::kAabb);
  EXPECT_TRUE(memory.Check(heavy, 1000, t0).ok());  // nothing known yet
  memory.Record(heavy, 1000, true, "step stopped at its deadline (during exact)", t0);

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
  EXPECT_TRUE(memory.Check(heavy, 1000, t0 + 30s).ok());  // time to measure again
}

TEST(DeadlineMemoryTest, AStepOfTheSameRequestThatFitsForgetsIt) {
  DeadlineMemory memory(30s);
  const auto t0 = Clock::now();
  const StepRequest heavy = Request(Method::kAabb);
  memory.Record(heavy, 1000, true, "stopped", t0);
  memory.Record(Request(Method::kBvh), 1000, false, "", t0 + 1s);  // another request: no change
  EXPECT_FALSE(memory.Check(heavy, 1000, t0 + 2s).ok());
  memory.Record(heavy, 1000, false, "", t0 + 31s);  // the recheck finished in time
  EXPECT_TRUE(memory.Check(heavy, 1000, t0 + 32s).ok());
}

}  // namespace
}  // namespace far::server
