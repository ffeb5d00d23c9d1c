// The CPU culls in front of the exact tests (sweep-and-prune on object boxes, the aabb method's
// triangle boxes) drop no pair the exact tests report. TrianglesWithinDistance accepts pairs up
// to D plus its error bound, so a pair just beyond D is reported by `exact` (the brute-force
// reference); a cull that grew boxes by D alone dropped it, and aabb then answered differently
// from exact (the cpu_methods fuzz target found it at a tiny scale).

#include <cmath>

#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far {
namespace {

// Two parallel triangles `gap` apart along z, the upper one placed by `motion`'s usual update.
std::vector<std::pair<Method, size_t>> DistancePairs(double gap, double distance) {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok());
  if (!pipeline.ok()) return {};
  const Mesh triangle{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
  EXPECT_TRUE((*pipeline)->AddObject(1, triangle, Motion::kStatic, {}).ok());
  Pose above;
  above.translation = Eigen::Vector3d(0.25, 0.25, gap);
  EXPECT_TRUE((*pipeline)->AddObject(2, triangle, Motion::kRigid, above).ok());
  std::vector<std::pair<Method, size_t>> found;
  for (Method method : {Method::kExact, Method::kAabb, Method::kBvh, Method::kAuto}) {
    StepRequest request;
    request.method = method;
    request.distance = distance;
    request.output = Output::kDistancePairs;
    auto result = (*pipeline)->Step(request);
    EXPECT_TRUE(result.ok()) << ToString(result.error());
    found.emplace_back(method, result.ok() ? result->distance_pairs.size() : SIZE_MAX);
  }
  return found;
}

TEST(CpuCullsTest, EveryMethodReportsWhatExactReportsAroundTheLimit) {
  const double d = 0.5;
  // Within D, exactly at D, just beyond it (inside the predicate's error bound: exact reports
  // the pair), and clearly beyond (nobody does).
  for (const auto& [gap, pairs] : {std::pair{0.25, 1u}, {d, 1u}, {d + 0x1p-50, 1u}, {0.75, 0u}}) {
    SCOPED_TRACE(gap);
    for (const auto& [method, count] : DistancePairs(gap, d)) {
      EXPECT_EQ(count, pairs) << ToString(method);
    }
  }
}

}  // namespace
}  // namespace far
