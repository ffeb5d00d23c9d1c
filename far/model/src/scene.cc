// Motion names, Pose, and ValidateScene: the meaning checks shared by ReadScene and WriteScene.

#include "far/model/scene.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "far/model/mesh.h"

namespace far {

const char* ToString(Motion motion) {
  switch (motion) {
    case Motion::kStatic:
      return "static";
    case Motion::kRigid:
      return "rigid";
    case Motion::kDeformable:
      return "deformable";
  }
  return "unknown";
}

std::optional<Motion> ParseMotion(std::string_view text) {
  if (text == "static") return Motion::kStatic;
  if (text == "rigid") return Motion::kRigid;
  if (text == "deformable") return Motion::kDeformable;
  return std::nullopt;
}

Eigen::Isometry3d Pose::ToIsometry() const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotation.toRotationMatrix();
  X.translation() = translation;
  return X;
}

namespace {

Error Invalid(const std::string& where, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument, where + ": " + what);
}

std::string Short(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return buffer;
}

// `where` is the JSON path of the object holding translation and rotation_wxyz.
Result<void> ValidatePose(const Pose& pose, const std::string& where) {
  if (!pose.translation.allFinite()) return Invalid(where + ".translation", "not finite");
  if (!pose.rotation.coeffs().allFinite()) return Invalid(where + ".rotation_wxyz", "not finite");
  const double norm = pose.rotation.norm();
  if (std::abs(norm - 1.0) > 1e-6) {
    return Invalid(where + ".rotation_wxyz", "not a unit quaternion (norm " + Short(norm) + ")");
  }
  return {};
}

Result<void> ValidateObject(const SceneObject& object, const std::string& where) {
  if (Result<void> mesh = ValidateMesh(object.mesh); !mesh.ok()) {
    return MakeError(mesh.error().code, where + ".mesh: object " + std::to_string(object.id) +
                                            ": " + mesh.error().message);
  }
  return ValidatePose(object.X_WO, where + ".pose");
}

// What the bookkeeping knows about an object alive at the current frame.
struct Alive {
  Motion motion;
  const Mesh* mesh;
};

}  // namespace

Result<void> ValidateScene(const Scene& scene) {
  std::unordered_map<uint32_t, Alive> alive;
  // Frame 0: the objects, each valid, ids unique.
  std::unordered_map<uint32_t, size_t> first_index;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& object = scene.objects[i];
    const std::string where = "objects[" + std::to_string(i) + "]";
    if (Result<void> status = ValidateObject(object, where); !status.ok()) return status;
    if (const auto it = first_index.find(object.id); it != first_index.end()) {
      return Invalid(where + ".id", "duplicate id " + std::to_string(object.id) +
                                        " (also objects[" + std::to_string(it->second) + "])");
    }
    first_index.emplace(object.id, i);
    alive.emplace(object.id, Alive{object.motion, &object.mesh});
  }
  // Each frame in order: removals, additions, poses, vertices.
  for (size_t f = 0; f < scene.frames.size(); ++f) {
    const FrameUpdate& frame = scene.frames[f];
    const std::string where_frame = "frames[" + std::to_string(f) + "]";
    for (size_t j = 0; j < frame.removals.size(); ++j) {
      const uint32_t id = frame.removals[j];
      if (alive.erase(id) == 0) {
        return MakeError(ErrorCode::kNotFound, where_frame + ".remove[" + std::to_string(j) +
                                                   "]: object " + std::to_string(id) +
                                                   " is not in the scene at this frame");
      }
    }
    for (size_t j = 0; j < frame.additions.size(); ++j) {
      const SceneObject& object = frame.additions[j];
      const std::string where = where_frame + ".add[" + std::to_string(j) + "]";
      if (Result<void> status = ValidateObject(object, where); !status.ok()) return status;
      if (!alive.emplace(object.id, Alive{object.motion, &object.mesh}).second) {
        return Invalid(where + ".id",
                       "object " + std::to_string(object.id) + " already exists at this frame");
      }
    }
    std::unordered_set<uint32_t> posed;
    for (size_t j = 0; j < frame.poses.size(); ++j) {
      const auto& [id, X_WO] = frame.poses[j];
      const std::string where = where_frame + ".poses[" + std::to_string(j) + "]";
      const auto it = alive.find(id);
      if (it == alive.end()) {
        return MakeError(ErrorCode::kNotFound, where + ".id: object " + std::to_string(id) +
                                                   " is not in the scene at this frame");
      }
      if (it->second.motion == Motion::kStatic) {
        return Invalid(where + ".id",
                       "object " + std::to_string(id) + " is static; static objects take no poses");
      }
      if (!posed.insert(id).second) {
        return Invalid(where + ".id",
                       "second pose for object " + std::to_string(id) + " in one frame");
      }
      if (Result<void> status = ValidatePose(X_WO, where); !status.ok()) return status;
    }
    std::unordered_set<uint32_t> deformed;
    for (size_t j = 0; j < frame.vertices.size(); ++j) {
      const auto& [id, mesh] = frame.vertices[j];
      const std::string where = where_frame + ".vertices[" + std::to_string(j) + "]";
      const auto it = alive.find(id);
      if (it == alive.end()) {
        return MakeError(ErrorCode::kNotFound, where + ".id: object " + std::to_string(id) +
                                                   " is not in the scene at this frame");
      }
      if (it->second.motion != Motion::kDeformable) {
        return Invalid(where + ".id", "object " + std::to_string(id) + " is " +
                                          ToString(it->second.motion) +
                                          "; only deformable objects take vertices");
      }
      if (!deformed.insert(id).second) {
        return Invalid(where + ".id",
                       "second vertex update for object " + std::to_string(id) + " in one frame");
      }
      const Mesh& current = *it->second.mesh;
      if (mesh.p_MV.size() != current.p_MV.size()) {
        return Invalid(where + ".mesh", "vertex file has " + std::to_string(mesh.p_MV.size()) +
                                            " vertices, object " + std::to_string(id) + " has " +
                                            std::to_string(current.p_MV.size()));
      }
      if (mesh.triangles.size() != current.triangles.size()) {
        return Invalid(where + ".mesh", "vertex file has " + std::to_string(mesh.triangles.size()) +
                                            " triangles, object " + std::to_string(id) + " has " +
                                            std::to_string(current.triangles.size()));
      }
      for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (mesh.triangles[t] != current.triangles[t]) {
          return Invalid(where + ".mesh", "vertex file's triangle " + std::to_string(t) +
                                              " differs from object " + std::to_string(id) +
                                              "'s (same triangles required)");
        }
      }
      for (size_t v = 0; v < mesh.p_MV.size(); ++v) {
        if (!mesh.p_MV[v].allFinite()) {
          return Invalid(where + ".mesh", "vertex " + std::to_string(v) + " is not finite");
        }
      }
    }
  }
  return {};
}

}  // namespace far
