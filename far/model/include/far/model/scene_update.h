#pragma once

// The four ways a scene changes between steps. Clients write them into the update ring, scene
// files hold them as frames, and far::Pipeline applies them; far::SceneModel checks them.

#include <cstdint>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "far/model/mesh.h"
#include "far/model/pose.h"

namespace far {

/// An object appears: its mesh in its own frame O, how it may move, and X_WO.
struct AddObject {
  uint32_t id = 0;
  Mesh mesh;
  Motion motion = Motion::kStatic;
  Pose X_WO;
};

/// An object disappears.
struct RemoveObject {
  uint32_t id = 0;
};

/// A rigid or deformable object moves to a new pose X_WO.
struct SetPose {
  uint32_t id = 0;
  Pose X_WO;
};

/// A deformable object's vertices move (frame O; same count, same triangles).
struct SetVertices {
  uint32_t id = 0;
  std::vector<Eigen::Vector3d> p_MV;
};

using SceneUpdate = std::variant<AddObject, RemoveObject, SetPose, SetVertices>;

/// Returns the id of the object `update` is about.
uint32_t ObjectIdOf(const SceneUpdate& update);

/// Returns "add_object", "remove_object", "set_pose" or "set_vertices".
const char* UpdateName(const SceneUpdate& update);

}  // namespace far
