#pragma once

// A scene: objects with meshes, motion kinds and poses, plus an optional animation (frames).
// Read and written as `far-scene/1` JSON by far/io/scene_io.h; the format is documented in
// docs/scene-format.md.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "far/base/result.h"
#include "far/model/mesh.h"
#include "far/model/pose.h"

namespace far {

/// One object of a scene.
struct SceneObject {
  uint32_t id = 0;        ///< unique among the objects alive at any frame
  std::string mesh_path;  ///< as written in the scene file: relative to the scene file's folder
  Mesh mesh;              ///< vertex positions in the object frame O
  Motion motion = Motion::kStatic;
  Pose X_WO;  ///< pose of the object frame O in the world frame W
  /// Optional label for people ("leaf-12", "tree"), shown where contacts are listed or drawn;
  /// empty: none. Need not be unique; at most kMaxObjectNameBytes bytes, no control characters.
  std::string name = {};  // (a default initializer: aggregates may leave it out)
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

/// Checks the meaning of a scene (what ReadScene checks after the JSON shape) with the rules of
/// far::SceneModel, update by update in frame order (removals, additions, poses, vertices):
/// valid meshes, unique ids, valid poses (CheckPose), poses only for alive rigid or deformable
/// objects, vertices only for alive deformable objects with the same vertex count; plus the
/// file format's own rules: vertex files with the object's triangles, at most one pose and one
/// vertex update per id and frame, names of at most kMaxObjectNameBytes bytes without control
/// characters. Errors name the place as a JSON path, e.g.
/// "frames[1].poses[0].id: object 4 is static; static objects take no poses":
/// kInvalidArgument for bad values, kNotFound for ids that are not alive.
Result<void> ValidateScene(const Scene& scene);

/// The objects alive at step `step` of a valid scene (ValidateScene), as `far-client play`
/// numbers steps: step 0 is `objects`, step k is after frames[0..k-1] are applied (removals,
/// additions, poses, vertices; additions go last, in frame order). Errors: kInvalidArgument
/// when step > frames.size() ("step 9: the scene has steps 0..4").
Result<std::vector<SceneObject>> ObjectsAtStep(const Scene& scene, size_t step);

}  // namespace far
