// The range of coordinates far answers exactly: positions and translations beyond
// +-kMaxCoordinate are refused in-process as they are on the ring, and world coordinates below
// kTinyWorldCoordinate are 0 for every method (world_object.h says why).

#include <cmath>
#include <string>

#include "cpu_pipeline.h"
#include <gtest/gtest.h>

#include "far/base/limits.h"
#include "far/pairs/world_object.h"
#include "far/pipeline/pipeline.h"

namespace far {
namespace {

using testing::CpuPipeline;

void ExpectRefused(const Result<void>& result, const std::string& field) {
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(result.error().message.find(field), std::string::npos) << result.error().message;
  EXPECT_NE(result.error().message.find("beyond +-1e+12"), std::string::npos)
      << result.error().message;
}

TEST(WorldCoordinatesTest, CoordinatesBeyondTheLimitAreRefusedInProcess) {
  auto pipeline = CpuPipeline();
  ASSERT_NE(pipeline, nullptr);
  const Mesh at_limit{{{-kMaxCoordinate, 0, 0}, {0, kMaxCoordinate, 0}, {0, 0, 1}}, {{0, 1, 2}}};
  Pose far_out;
  far_out.translation = Eigen::Vector3d(0, 0, -kMaxCoordinate);
  ASSERT_TRUE(pipeline->AddObject(1, at_limit, Motion::kDeformable, far_out).ok());

  const double beyond = std::nextafter(kMaxCoordinate, 2 * kMaxCoordinate);
  ExpectRefused(pipeline->AddObject(2, Mesh{{{0, 0, 0}, {beyond, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}},
                                    Motion::kRigid, {}),
                "mesh: vertex 1");
  Pose beyond_pose;
  beyond_pose.translation = Eigen::Vector3d(0, -beyond, 0);
  ExpectRefused(pipeline->AddObject(2, at_limit, Motion::kRigid, beyond_pose), "translation");
  ExpectRefused(pipeline->SetPose(1, beyond_pose), "translation");
  ExpectRefused(pipeline->SetVertices(1, {{0, 0, 0}, {0, 0, 1e13}, {0, 1, 0}}), "vertex 1");
  // Nothing refused changed the scene: one object, still at the limit.
  EXPECT_EQ(pipeline->num_triangles(), 1);
  EXPECT_TRUE(pipeline->SetVertices(1, at_limit.p_MV).ok());
}

TEST(WorldCoordinatesTest, FlushTinyCoordinatesKeepsEverythingElse) {
  const double tiny = kTinyWorldCoordinate;
  EXPECT_EQ(FlushTinyCoordinates({tiny, -tiny, 0.5 * tiny}), Eigen::Vector3d(tiny, -tiny, 0));
  EXPECT_EQ(FlushTinyCoordinates({std::nextafter(tiny, 0.0), -1e-300, 5e-324}),
            Eigen::Vector3d::Zero());
  EXPECT_EQ(FlushTinyCoordinates({1, -3e12, 1e-70}), Eigen::Vector3d(1, -3e12, 1e-70));
}

// The contacts of a static triangle in the plane x = 0 with `other` (posed by X_WO).
size_t ContactsWithThePlane(Method method, const Mesh& other, Motion motion, const Pose& X_WO) {
  auto pipeline = CpuPipeline();
  if (pipeline == nullptr) return SIZE_MAX;
  EXPECT_TRUE(pipeline
                  ->AddObject(1, Mesh{{{0, 0, -1}, {0, 2, -1}, {0, 1, 1}}, {{0, 1, 2}}},
                              Motion::kStatic, {})
                  .ok());
  EXPECT_TRUE(pipeline->AddObject(2, other, motion, X_WO).ok());
  StepRequest request;
  request.method = method;
  auto result = pipeline->Step(request);
  EXPECT_TRUE(result.ok()) << ToString(result.error());
  return result.ok() ? result->contacts.size() : SIZE_MAX;
}

// A static triangle in the plane x = 0, and a rigid one whose corner (0, 1, 0) lies on it in its
// own frame. Turned about z by 2^-400, that corner's world x is -2^-400: below
// kTinyWorldCoordinate, so 0, and the triangles touch; moved 2^-200 away along -x (not tiny),
// they are apart. Every CPU method gives the same answer, the hierarchy's included (its descent
// runs on the unflushed meshes, and its margin covers the flush).
size_t Contacts(Method method, double shift_x) {
  Pose turned;
  turned.rotation = Eigen::Quaterniond(1, 0, 0, 0x1p-401);  // unit: 1 + 2^-802 rounds to 1
  turned.translation = Eigen::Vector3d(shift_x, 0, 0);
  return ContactsWithThePlane(method, Mesh{{{0, 1, 0}, {-1, 1, 0}, {-1, 1, 1}}, {{0, 1, 2}}},
                              Motion::kRigid, turned);
}

TEST(WorldCoordinatesTest, TinyWorldCoordinatesAreZeroForEveryMethod) {
  for (Method method : {Method::kExact, Method::kBvh, Method::kAabb, Method::kAuto}) {
    SCOPED_TRACE(static_cast<int>(method));
    EXPECT_EQ(Contacts(method, 0), 1u);
    EXPECT_EQ(Contacts(method, -0x1p-200), 0u);
  }
}

// The same at the identity pose, which the pipeline maps without products: a deformable
// triangle whose corner lies at x = -2^-400 in its own frame touches the plane x = 0 (the corner
// is flushed to 0), and one 2^-200 away does not.
size_t ContactsAtIdentity(Method method, double corner_x) {
  return ContactsWithThePlane(method, Mesh{{{corner_x, 1, 0}, {-1, 1, 0}, {-1, 1, 1}}, {{0, 1, 2}}},
                              Motion::kDeformable, {});
}

TEST(WorldCoordinatesTest, TinyCoordinatesAreZeroAtTheIdentityPoseToo) {
  for (Method method : {Method::kExact, Method::kBvh, Method::kAabb, Method::kAuto}) {
    SCOPED_TRACE(static_cast<int>(method));
    EXPECT_EQ(ContactsAtIdentity(method, -0x1p-400), 1u);
    EXPECT_EQ(ContactsAtIdentity(method, -0x1p-200), 0u);
  }
}

}  // namespace
}  // namespace far
