// The geometry stage through the pipeline (StepRequest::geometry): arrays parallel to the
// contacts and distance pairs, nothing when not asked, and fcl#106's case: a box resting on a
// bigger one gives contact points on the face they share (never outside it), and a box sunk
// into the other gives the overlap depth along the face normal.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "far/geometry/triangle_tests.h"
#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

using Eigen::Vector3d;
using scenes::BoxMesh;

class GeometryStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    PipelineOptions options;
    options.use_gl = false;
    options.num_threads = 2;
    auto pipeline = Pipeline::Create(options);
    ASSERT_TRUE(pipeline.ok()) << ToString(pipeline.error());
    pipeline_ = std::move(*pipeline);
  }

  StepResult Step(StepRequest request) {
    auto result = pipeline_->Step(request);
    EXPECT_TRUE(result.ok()) << ToString(result.error());
    return result.ok() ? std::move(*result) : StepResult{};
  }

  // The world triangle `t` of the box with id `id` (both boxes are static, at the identity).
  TrianglePoints Triangle(const Mesh& mesh, uint32_t t) const {
    const TriangleIndices& v = mesh.triangles[t];
    return {mesh.p_MV[v[0]], mesh.p_MV[v[1]], mesh.p_MV[v[2]]};
  }

  std::unique_ptr<Pipeline> pipeline_;
};

TEST_F(GeometryStageTest, BoxRestingOnABoxHasContactPointsOnTheSharedFaceOnly) {
  // fcl#106: a small box resting on a big one. Expected: points on the small box's bottom face
  // (z = 1, x and y in [0.25, 0.75]), its four corners among them, and nothing outside it.
  const Mesh big = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh small = BoxMesh({0.25, 0.25, 1}, {0.75, 0.75, 1.5});
  ASSERT_TRUE(pipeline_->AddObject(1, big, Motion::kStatic, {}).ok());
  ASSERT_TRUE(pipeline_->AddObject(2, small, Motion::kStatic, {}).ok());
  for (Method method : {Method::kBvh, Method::kExact, Method::kAabb}) {
    StepRequest request;
    request.method = method;
    request.geometry = true;
    const StepResult result = Step(request);
    ASSERT_FALSE(result.contacts.empty());
    ASSERT_EQ(result.contact_geometry.size(), result.contacts.size());
    std::vector<Vector3d> corners = {
        {0.25, 0.25, 1}, {0.75, 0.25, 1}, {0.25, 0.75, 1}, {0.75, 0.75, 1}};
    for (size_t i = 0; i < result.contacts.size(); ++i) {
      const ContactGeometry& g = result.contact_geometry[i];
      ASSERT_GE(g.num_points, 1);
      for (int k = 0; k < g.num_points; ++k) {
        const Vector3d& p = g.points[k];
        EXPECT_EQ(p.z(), 1.0);
        EXPECT_TRUE(p.x() >= 0.25 && p.x() <= 0.75 && p.y() >= 0.25 && p.y() <= 0.75)
            << ToString(method) << ": contact point " << p.transpose() << " off the face";
        corners.erase(std::remove(corners.begin(), corners.end(), p), corners.end());
      }
      EXPECT_NEAR(std::abs(g.normal_a.z()), 1.0, 1e-15);
    }
    EXPECT_TRUE(corners.empty()) << ToString(method) << ": a corner of the face is missing";
    ASSERT_EQ(result.penetrations.size(), 1u);
    EXPECT_TRUE(result.penetrations[0].closed);
    EXPECT_EQ(result.penetrations[0].depth, 0.0);  // touching, not overlapping
  }
}

TEST_F(GeometryStageTest, SunkBoxGivesTheOverlapDepthAlongTheFaceNormal) {
  const double sink = 0.01;
  const Mesh big = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh small = BoxMesh({0.25, 0.25, 1 - sink}, {0.75, 0.75, 1.5});
  ASSERT_TRUE(pipeline_->AddObject(1, big, Motion::kStatic, {}).ok());
  ASSERT_TRUE(pipeline_->AddObject(2, small, Motion::kStatic, {}).ok());
  StepRequest request;
  request.method = Method::kBvh;
  request.geometry = true;
  const StepResult result = Step(request);
  ASSERT_EQ(result.penetrations.size(), 1u);
  const Penetration& p = result.penetrations[0];
  EXPECT_EQ(p.object_a, 1u);
  EXPECT_EQ(p.object_b, 2u);
  EXPECT_TRUE(p.closed);
  EXPECT_NEAR(p.depth, sink, 1e-15);
  // Moving object b (the small box) by depth * direction lifts it out: +z.
  EXPECT_NEAR(p.direction.z(), 1.0, 1e-15);
  EXPECT_NEAR((p.point_a - p.point_b).norm(), p.depth, 1e-15);
  // Every contact point lies on both of its triangles.
  for (size_t i = 0; i < result.contacts.size(); ++i) {
    const ContactPair& c = result.contacts[i];
    const TrianglePoints ta = Triangle(big, c.triangle_a);
    const TrianglePoints tb = Triangle(small, c.triangle_b);
    for (int k = 0; k < result.contact_geometry[i].num_points; ++k) {
      const Vector3d& x = result.contact_geometry[i].points[k];
      const TrianglePoints point{x, x, x};
      EXPECT_LE(TriangleDistance(point, ta), 1e-15);
      EXPECT_LE(TriangleDistance(point, tb), 1e-15);
    }
  }
}

TEST_F(GeometryStageTest, DistancePairsGetTheirClosestPointsAndOpenMeshesNoDepth) {
  // Two single triangles (open meshes) 0.25 apart.
  const Mesh triangle{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
  Pose above;
  above.translation = Vector3d(0.25, 0.25, 0.25);
  ASSERT_TRUE(pipeline_->AddObject(1, triangle, Motion::kStatic, {}).ok());
  ASSERT_TRUE(pipeline_->AddObject(2, triangle, Motion::kRigid, above).ok());
  StepRequest request;
  request.method = Method::kBvh;
  request.distance = 0.5;
  request.output = Output::kDistancePairs;
  request.geometry = true;
  StepResult result = Step(request);
  ASSERT_EQ(result.distance_pairs.size(), 1u);
  ASSERT_EQ(result.closest_points.size(), 1u);
  const ClosestPoints& c = result.closest_points[0];
  EXPECT_EQ((c.point_b - c.point_a).norm(), result.distance_pairs[0].distance);
  EXPECT_EQ(c.point_a.z(), 0.0);
  EXPECT_EQ(c.point_b.z(), 0.25);
  EXPECT_TRUE(result.penetrations.empty());  // no contact

  // Crossing: a contact of two open meshes has geometry, and its penetration says "not closed".
  above.translation = Vector3d(0.25, 0.25, -0.25);
  Pose tilted = above;
  tilted.rotation = Eigen::AngleAxisd(0.5, Vector3d::UnitX());
  ASSERT_TRUE(pipeline_->SetPose(2, tilted).ok());
  request.distance.reset();
  request.output = Output::kContacts;
  result = Step(request);
  ASSERT_EQ(result.contacts.size(), 1u);
  ASSERT_EQ(result.contact_geometry.size(), 1u);
  EXPECT_EQ(result.contact_geometry[0].num_points, 2);
  ASSERT_EQ(result.penetrations.size(), 1u);
  EXPECT_FALSE(result.penetrations[0].closed);
  EXPECT_EQ(result.penetrations[0].depth, 0.0);
}

TEST_F(GeometryStageTest, NothingIsComputedUnlessAsked) {
  ASSERT_TRUE(pipeline_->AddObject(1, BoxMesh({0, 0, 0}, {1, 1, 1}), Motion::kStatic, {}).ok());
  ASSERT_TRUE(
      pipeline_->AddObject(2, BoxMesh({0.5, 0.5, 0.5}, {2, 2, 2}), Motion::kStatic, {}).ok());
  StepRequest request;
  request.method = Method::kBvh;
  StepResult result = Step(request);
  EXPECT_FALSE(result.contacts.empty());
  EXPECT_TRUE(result.contact_geometry.empty());
  EXPECT_TRUE(result.penetrations.empty());
  for (const StageStats& stage : result.stats.stages) EXPECT_NE(stage.stage, Stage::kGeometry);
  request.geometry = true;
  result = Step(request);
  EXPECT_EQ(result.stats.stages.back().stage, Stage::kGeometry);
  // Geometry needs contacts or distance pairs to describe.
  request.output = Output::kPrimitivePcs;
  auto refused = pipeline_->Step(request);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(refused.error().message.find("geometry"), std::string::npos);
}

}  // namespace
}  // namespace far
