// far::CheckStepRequest and far::Quantile: the shared request rule and the shared quantile.

#include "far/model/step_request.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "far/base/limits.h"
#include "far/base/quantile.h"

namespace far {
namespace {

void ExpectInvalid(const StepRequest& request, const std::string& substring) {
  const Result<void> checked = CheckStepRequest(request);
  ASSERT_FALSE(checked) << "accepted; expected " << substring;
  EXPECT_EQ(checked.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(checked.error().message.find(substring), std::string::npos) << checked.error().message;
}

TEST(CheckStepRequestTest, AcceptsTheLimitsThemselves) {
  StepRequest request;
  for (int resolution : {kMinResolution, kMaxResolution}) {
    request.resolution = resolution;
    EXPECT_TRUE(CheckStepRequest(request));
  }
  request.subobject_size = kMaxSubobjectSize;
  request.distance = kMaxDistance;
  request.output = Output::kDistancePairs;
  EXPECT_TRUE(CheckStepRequest(request));
}

TEST(CheckStepRequestTest, RejectsEachOutOfRangeField) {
  StepRequest request;
  request.resolution = kMaxResolution + 1;
  ExpectInvalid(request, "resolution: 8193 is outside [8, 8192]");
  request = {};
  request.subobject_size = 0;
  ExpectInvalid(request, "subobject_size: 0 is outside [1, 1048576]");
  for (double d : {-1.0, std::nan(""), std::numeric_limits<double>::infinity(), 2 * kMaxDistance}) {
    request = {};
    request.distance = d;
    ExpectInvalid(request, "distance: ");
  }
  request = {};
  request.output = Output::kDistancePairs;
  ExpectInvalid(request, "output: 'distance' needs a distance D");
  request = {};
  request.method = Method::kFcl;
  request.distance = 0.1;
  ExpectInvalid(request, "method: 'fcl' answers contacts only");
}

// The refusal names every method that does answer a distance, bvh included.
TEST(CheckStepRequestTest, FclWithADistanceNamesEveryMethodThatAnswersDistances) {
  StepRequest request;
  request.method = Method::kFcl;
  request.distance = 0.1;
  ExpectInvalid(request,
                "distance queries need auto, aabb, bvh, gpu, cullide, far, far-exact-offset or exact");
}

TEST(QuantileTest, InterpolatesBetweenRanks) {
  EXPECT_DOUBLE_EQ(Quantile({}, 0.5), 0);
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 0.0), 1);
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 1.0), 4);
  EXPECT_DOUBLE_EQ(Quantile({7}, 0.99), 7);
}

}  // namespace
}  // namespace far
