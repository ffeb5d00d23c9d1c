#include "far/base/assert.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace far {
namespace {

// The handler tests install: leaves AssertionFailed by an exception that carries its report.
struct CheckFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};
void Throw(const internal::AssertionFailure& failure) {
  throw CheckFailed(std::string(failure.condition) + " | " + std::string(failure.message) + " | " +
                    failure.file + ":" + std::to_string(failure.line));
}

class AssertTest : public ::testing::Test {
 protected:
  void SetUp() override { previous_ = internal::SetAssertionHandler(&Throw); }
  void TearDown() override { internal::SetAssertionHandler(previous_); }

 private:
  internal::AssertionHandler previous_ = nullptr;
};

TEST_F(AssertTest, DemandReportsConditionMessageAndPlaceWhenItFails) {
  const int slot = 7, size = 3;
  try {
    FAR_DEMAND(slot < size, "a slot of the step");
    FAIL() << "FAR_DEMAND let a false condition pass";
  } catch (const CheckFailed& failed) {
    const std::string report = failed.what();
    EXPECT_NE(report.find("slot < size"), std::string::npos) << report;
    EXPECT_NE(report.find("a slot of the step"), std::string::npos) << report;
    EXPECT_NE(report.find("assert_test.cc:"), std::string::npos) << report;
  }
}

TEST_F(AssertTest, DemandEvaluatesItsConditionOnceAndPassesWhenTrue) {
  int evaluations = 0;
  FAR_DEMAND(++evaluations == 1, "counted");
  EXPECT_EQ(evaluations, 1);
}

TEST_F(AssertTest, AssertChecksOnlyInDebugBuildsAndNeverEvaluatesOtherwise) {
  int evaluations = 0;
#ifdef NDEBUG
  FAR_ASSERT(++evaluations < 0, "compiled out");
  EXPECT_EQ(evaluations, 0);
#else
  EXPECT_THROW(FAR_ASSERT(++evaluations < 0, "checked in debug builds"), CheckFailed);
  EXPECT_EQ(evaluations, 1);
#endif
}

}  // namespace
}  // namespace far
