#pragma once

// A scene: objects with meshes, motion kinds and poses, plus an optional animation (frames).
// Read and written as `far-scene/1` JSON by far/scene_io.h; the format is documented in
// docs/scene-format.md.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/mesh.h"
#include "far/model/result.h"

namespace far {

/// How an object may change over the frames of a scene.
enum class Motion {
  kStatic,      ///< never moves: no pose or vertex updates
  kRigid,       ///< moves by pose updates
  kDeformable,  ///< moves by pose and vertex updates (same triangles, new positions)
};

/// Returns the scene-file name of `motion`: "static", "rigid" or "deformable".
const char* ToString(Motion motion);

/// Parses "static", "rigid" or "deformable"; nullopt for anything else.
std::optional<Motion> ParseMotion(std::string_view text);

/// A rigid transform: a rotation, then a translation. Default: identity.
struct Pose {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit quaternion

  /// Returns the transform x -> rotation * x + translation.
  Eigen::Isometry3d ToIsometry() const;
};

/// One object of a scene.
struct SceneObject {
  uint32_t id = 0;        ///< unique among the objects alive at any frame
  std::string mesh_path;  ///< as written in the scene file: relative to the scene file's folder
  Mesh mesh;              ///< vertex positions in the object frame O
  Motion motion = Motion::kStatic;
  Pose X_WO;  ///< pose of the object frame O in the world frame W
};

/// One animation step, applied in this order: removals, additions, poses, vertices.
struct FrameUpdate {
  /// New poses X_WO by object id (rigid or deformable objects only).
  std::vector<std::pair<uint32_t, Pose>> poses;
  /// New vertex positions by object id (deformable objects only): a mesh with the same vertex
  /// count and the same triangles as the object's mesh.
  std::vector<std::pair<uint32_t, Mesh>> vertices;
  /// vertex_mesh_paths[i] is the file vertices[i] came from, as written in the scene file.
  /// WriteScene uses it when it has the same size as `vertices` and the entry is not empty,
  /// and otherwise makes up a name; readers always fill it.
  std::vector<std::string> vertex_mesh_paths;
  /// Objects that appear at this step (ids not alive at this point).
  std::vector<SceneObject> additions;
  /// Ids of objects that disappear at this step (alive at this point).
  std::vector<uint32_t> removals;
};

/// Objects at frame 0, then the updates of frames 1, 2, ...
struct Scene {
  std::vector<SceneObject> objects;
  std::vector<FrameUpdate> frames;
};

/// Checks the meaning of a scene (what ReadScene checks after the JSON shape): every mesh
/// valid, unique ids, unit rotation quaternions (norm within 1e-6 of 1) and finite poses, and,
/// frame by frame with the id bookkeeping applied in order: removals of alive ids, additions of
/// ids not alive, poses only for alive rigid or deformable objects, vertices only for alive
/// deformable objects with the same vertex count and triangles, at most one pose and one vertex
/// update per id and frame. Errors name the place as a JSON path, e.g.
/// "frames[1].poses[0].id: object 4 is static; static objects take no poses":
/// kInvalidArgument for bad values, kNotFound for ids that are not alive.
Result<void> ValidateScene(const Scene& scene);

}  // namespace far
