// far::SceneModel: the one home of the scene rules that scene files, the daemon and the
// pipeline share.

#include "far/model/scene_model.h"

#include <cmath>

#include <gtest/gtest.h>

namespace far {
namespace {

Mesh Triangle() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

Result<void> ApplyAll(SceneModel& model, const std::vector<SceneUpdate>& updates) {
  return model.Apply(updates);
}

template <typename T>
::testing::AssertionResult IsError(const Result<T>& result, ErrorCode code,
                                   const std::string& substring) {
  if (result.ok()) return ::testing::AssertionFailure() << "accepted; expected " << substring;
  if (result.error().code != code || result.error().message.find(substring) == std::string::npos) {
    return ::testing::AssertionFailure() << "got " << ToString(result.error());
  }
  return ::testing::AssertionSuccess();
}

TEST(SceneModelTest, AddsPosesDeformsAndRemoves) {
  SceneModel model;
  ASSERT_TRUE(ApplyAll(model, {AddObject{7, Triangle(), Motion::kDeformable, {}}, SetPose{7, {}},
                               SetVertices{7, Triangle().p_MV}}));
  ASSERT_NE(model.Find(7), nullptr);
  EXPECT_EQ(model.Find(7)->num_vertices, 3u);
  EXPECT_EQ(model.num_triangles(), 1);
  ASSERT_TRUE(ApplyAll(model, {RemoveObject{7}}));
  EXPECT_EQ(model.Find(7), nullptr);
  EXPECT_EQ(model.num_triangles(), 0);
  EXPECT_EQ(model.num_vertices(), 0);
}

TEST(SceneModelTest, EnforcesEachRuleWithTheFieldFirst) {
  SceneModel model;
  ASSERT_TRUE(ApplyAll(model, {AddObject{1, Triangle(), Motion::kStatic, {}},
                               AddObject{2, Triangle(), Motion::kRigid, {}}}));
  SceneModel::Batch batch = model.Begin();
  EXPECT_TRUE(IsError(batch.Add(1, Triangle(), Motion::kRigid, {}), ErrorCode::kInvalidArgument,
                      "id: object 1 is already in the scene"));
  EXPECT_TRUE(IsError(batch.Remove(9), ErrorCode::kNotFound, "id: object 9 is not in the scene"));
  EXPECT_TRUE(IsError(batch.SetPose(1, {}), ErrorCode::kInvalidArgument,
                      "id: object 1 is static; static objects take no poses"));
  EXPECT_TRUE(IsError(batch.SetVertices(2, Triangle().p_MV), ErrorCode::kInvalidArgument,
                      "id: object 2 is rigid; only deformable objects take vertices"));
  Pose bad;
  bad.rotation = Eigen::Quaterniond(1.7, 0, 0, 0);
  EXPECT_TRUE(IsError(batch.SetPose(2, bad), ErrorCode::kInvalidArgument,
                      "rotation_wxyz: not a unit quaternion (norm 1.7)"));
  EXPECT_TRUE(IsError(batch.Add(3, Triangle(), Motion::kRigid, bad), ErrorCode::kInvalidArgument,
                      "pose.rotation_wxyz: not a unit quaternion"));
  Mesh broken = Triangle();
  broken.triangles[0][2] = 5;
  EXPECT_TRUE(IsError(batch.Add(3, broken, Motion::kRigid, {}), ErrorCode::kInvalidArgument,
                      "mesh: triangle 0: vertex index 5 out of range"));
}

TEST(SceneModelTest, ABatchSeesItsOwnUpdatesAndIsAllOrNothing) {
  SceneModel model;
  // Added then posed in one batch: fine. Removed then posed: not.
  ASSERT_TRUE(ApplyAll(model, {AddObject{4, Triangle(), Motion::kRigid, {}}, SetPose{4, {}}}));
  const Result<void> failed = ApplyAll(
      model, {RemoveObject{4}, AddObject{5, Triangle(), Motion::kStatic, {}}, SetPose{4, {}}});
  EXPECT_TRUE(IsError(failed, ErrorCode::kNotFound,
                      "update 2 (set_pose) id: object 4 is not in the scene"));
  // Nothing of the failed batch was applied.
  EXPECT_NE(model.Find(4), nullptr);
  EXPECT_EQ(model.Find(5), nullptr);
  EXPECT_EQ(model.num_objects(), 1);
}

TEST(SceneModelTest, CountsTheBudgetsOverTheBatch) {
  SceneLimits limits;
  limits.max_objects = 2;
  limits.max_triangles = 3;
  SceneModel model(limits);
  EXPECT_TRUE(IsError(ApplyAll(model, {AddObject{1, Triangle(), Motion::kStatic, {}},
                                       AddObject{2, Triangle(), Motion::kStatic, {}},
                                       AddObject{3, Triangle(), Motion::kStatic, {}}}),
                      ErrorCode::kLimitExceeded, "more than 2 objects"));
  // A removal in the same batch makes room.
  ASSERT_TRUE(ApplyAll(model, {AddObject{1, Triangle(), Motion::kStatic, {}},
                               AddObject{2, Triangle(), Motion::kStatic, {}}}));
  EXPECT_TRUE(ApplyAll(model, {RemoveObject{1}, AddObject{3, Triangle(), Motion::kStatic, {}}}));
  Mesh two = Triangle();
  two.triangles.push_back({0, 2, 1});
  // Objects 2 and 3 hold 2 triangles; a removal in the batch frees one for a 2-triangle mesh.
  EXPECT_TRUE(IsError(ApplyAll(model, {AddObject{4, two, Motion::kStatic, {}}}),
                      ErrorCode::kLimitExceeded, "more than 2 objects"));
  EXPECT_TRUE(ApplyAll(model, {RemoveObject{2}, AddObject{4, two, Motion::kStatic, {}}}));
  EXPECT_EQ(model.num_triangles(), 3);
  EXPECT_TRUE(IsError(ApplyAll(model, {RemoveObject{3}, AddObject{5, two, Motion::kStatic, {}}}),
                      ErrorCode::kLimitExceeded,
                      "mesh: the scene would have 4 triangles (limit 3)"));
}

TEST(SceneModelTest, EveryUint32IsAnId) {
  SceneModel model;
  EXPECT_TRUE(ApplyAll(model, {AddObject{0, Triangle(), Motion::kStatic, {}},
                               AddObject{0xFFFFFFFFu, Triangle(), Motion::kStatic, {}}}));
  EXPECT_EQ(model.num_objects(), 2);
}

TEST(SceneModelTest, PosesAreCheckedWithTheSharedTolerance) {
  Pose pose;
  pose.rotation = Eigen::Quaterniond(1 + 5e-7, 0, 0, 0);
  EXPECT_TRUE(CheckPose(pose));
  EXPECT_DOUBLE_EQ(NormalizedPose(pose).rotation.norm(), 1.0);
  // Four decimals, as people write them: |q| = 0.99999 ... accepted and normalized.
  pose.rotation = Eigen::Quaterniond(0.7071, 0, 0, 0.7071);
  const Result<Pose> unit = CheckAndNormalizePose(pose);
  ASSERT_TRUE(unit);
  EXPECT_NEAR(unit->rotation.norm(), 1.0, 1e-15);
  EXPECT_NEAR(unit->rotation.z(), std::sqrt(0.5), 1e-15);
  // Within kQuaternionTolerance = 1e-3 of 1, not beyond.
  pose.rotation = Eigen::Quaterniond(1 - 0.9e-3, 0, 0, 0);
  EXPECT_TRUE(CheckPose(pose));
  pose.rotation = Eigen::Quaterniond(1 + 1.1e-3, 0, 0, 0);
  EXPECT_TRUE(IsError(CheckAndNormalizePose(pose), ErrorCode::kInvalidArgument,
                      "rotation_wxyz: not a unit quaternion (norm 1.0011): |norm - 1| must be at "
                      "most 0.001"));
  pose.translation.x() = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(IsError(CheckPose(pose), ErrorCode::kInvalidArgument, "translation: not finite"));
}

}  // namespace
}  // namespace far
