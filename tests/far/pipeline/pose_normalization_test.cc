// A pose whose quaternion is within kQuaternionTolerance of unit norm (as written with four
// decimals, or as sent by a writer that does not normalize) is accepted, and the object is
// placed by the rotation it stands for: the normalized one, not the stretched map a non-unit
// quaternion gives.

#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far {
namespace {

Mesh Triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Mesh mesh;
  mesh.p_MV = {a, b, c};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

// Contacts between a triangle in the plane x = -1 of its own frame, turned half a turn about z
// by `rotation` (so into the plane x = 1), and a static triangle in the plane y = 0 whose edge
// nearest to it is at x = `edge_x`.
size_t Contacts(const Eigen::Quaterniond& rotation, double edge_x) {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 1;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok());
  if (!pipeline.ok()) return SIZE_MAX;
  Pose turned;
  turned.rotation = rotation;
  auto added = (*pipeline)->AddObject(1, Triangle({-1, -1, -1}, {-1, 1, -1}, {-1, 0, 1}),
                                      Motion::kRigid, turned);
  EXPECT_TRUE(added.ok()) << ToString(added.error());
  EXPECT_TRUE((*pipeline)->AddObject(2, Triangle({edge_x, 0, -0.5}, {edge_x, 0, 0.5}, {3, 0, 0}),
                                     Motion::kStatic, {}));
  StepRequest request;
  request.method = Method::kExact;
  auto result = (*pipeline)->Step(request);
  EXPECT_TRUE(result.ok()) << ToString(result.error());
  return result.ok() ? result->contacts.size() : SIZE_MAX;
}

TEST(PoseNormalizationTest, NearlyUnitQuaternionsPlaceObjectsByTheirRotation) {
  const Eigen::Quaterniond exact(0, 0, 0, 1);  // half a turn about z
  // |q| = 1.0009: within the tolerance. Used as it is, it would stretch x and y by |q|^2 and
  // move the plane x = 1 to x = 1.0036, into the static triangle.
  const Eigen::Quaterniond loose(0, 0, 0, 1.0009);
  EXPECT_EQ(Contacts(exact, 1.002), 0u);
  EXPECT_EQ(Contacts(loose, 1.002), 0u);
  // A hair closer, both touch: the check above is not vacuous.
  EXPECT_EQ(Contacts(exact, 0.998), 1u);
  EXPECT_EQ(Contacts(loose, 0.998), 1u);
  // Four decimals, 90 degrees about z then 90 more: the same answers as the exact rotation.
  const Eigen::Quaterniond quarter(0.7071, 0, 0, 0.7071);
  EXPECT_EQ(Contacts(quarter * quarter, 1.002), 0u);
  EXPECT_EQ(Contacts(quarter * quarter, 0.998), 1u);
}

TEST(PoseNormalizationTest, QuaternionsBeyondTheToleranceAreRefused) {
  PipelineOptions options;
  options.use_gl = false;
  auto pipeline = Pipeline::Create(options);
  ASSERT_TRUE(pipeline.ok());
  Pose stretched;
  stretched.rotation = Eigen::Quaterniond(0, 0, 0, 1.0011);
  auto added = (*pipeline)->AddObject(1, Triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}), Motion::kRigid,
                                      stretched);
  ASSERT_FALSE(added.ok());
  EXPECT_EQ(added.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(added.error().message.find("not a unit quaternion (norm 1.0011)"), std::string::npos)
      << added.error().message;
}

}  // namespace
}  // namespace far
