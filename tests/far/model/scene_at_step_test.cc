// ObjectsAtStep: the state of a scene at one step, frames applied in order.

#include <gtest/gtest.h>

#include "far/model/scene.h"

namespace far {
namespace {

SceneObject Object(uint32_t id, Motion motion, const std::string& name) {
  SceneObject object;
  object.id = id;
  object.motion = motion;
  object.name = name;
  object.mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  object.mesh.triangles = {{0, 1, 2}};
  return object;
}

TEST(ObjectsAtStepTest, AppliesRemovalsAdditionsPosesAndVerticesUpToTheStep) {
  Scene scene;
  scene.objects = {Object(1, Motion::kStatic, "ground"), Object(2, Motion::kRigid, "vase"),
                   Object(3, Motion::kDeformable, "leaf")};
  FrameUpdate first;
  first.poses.emplace_back(2, Pose{Eigen::Vector3d(0, 0, 1), Eigen::Quaterniond::Identity()});
  Mesh moved = scene.objects[2].mesh;
  moved.p_MV[0] = Eigen::Vector3d(0, 0, 5);
  first.vertices.emplace_back(3, moved);
  FrameUpdate second;
  second.removals = {2};
  second.additions = {Object(4, Motion::kRigid, "vase-fragment-1")};
  scene.frames = {first, second};
  ASSERT_TRUE(ValidateScene(scene));

  const auto at0 = ObjectsAtStep(scene, 0);
  ASSERT_TRUE(at0);
  ASSERT_EQ(at0->size(), 3u);
  EXPECT_EQ((*at0)[1].X_WO.translation, Eigen::Vector3d::Zero());

  const auto at1 = ObjectsAtStep(scene, 1);
  ASSERT_TRUE(at1);
  ASSERT_EQ(at1->size(), 3u);
  EXPECT_EQ((*at1)[1].X_WO.translation, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ((*at1)[2].mesh.p_MV[0], Eigen::Vector3d(0, 0, 5));

  const auto at2 = ObjectsAtStep(scene, 2);
  ASSERT_TRUE(at2);
  ASSERT_EQ(at2->size(), 3u);
  EXPECT_EQ((*at2)[0].name, "ground");
  EXPECT_EQ((*at2)[1].name, "leaf");
  EXPECT_EQ((*at2)[1].mesh.p_MV[0], Eigen::Vector3d(0, 0, 5)) << "vertices stay as last set";
  EXPECT_EQ((*at2)[2].name, "vase-fragment-1");

  const auto beyond = ObjectsAtStep(scene, 3);
  ASSERT_FALSE(beyond);
  EXPECT_EQ(beyond.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(beyond.error().message.find("step 3: the scene has steps 0..2"), std::string::npos)
      << beyond.error().message;
}

}  // namespace
}  // namespace far
