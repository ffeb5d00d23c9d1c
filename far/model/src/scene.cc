// ValidateScene: a scene file's objects and frames, checked by the scene model update by update
// (so a scene far-client accepts is one the daemon and the pipeline accept), plus the two
// rules of the file format itself: at most one pose and one vertex update per object and frame,
// and vertex files with the object's own triangles.

#include "far/model/scene.h"

#include <string>
#include <unordered_map>
#include <unordered_set>

#include "far/base/limits.h"
#include "far/model/scene_model.h"

namespace far {
namespace {

Error Invalid(const std::string& where, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument, where + ": " + what);
}

// The model's error (its message starts with the field) at the JSON path `where`.
Error At(const std::string& where, const Error& error) {
  return MakeError(error.code, where + "." + error.message);
}

// As At, for a path that is the id itself (frames[f].remove[j]): drops the model's "id" field.
Error AtId(const std::string& where, const Error& error) {
  const std::string& message = error.message;
  return MakeError(error.code,
                   where + (message.rfind("id:", 0) == 0 ? message.substr(2) : ": " + message));
}

// Checks that a vertex file has the object's triangles; the message says where they differ.
Result<void> SameTriangles(const Mesh& file, const Mesh& object, uint32_t id) {
  const std::string name = "object " + std::to_string(id);
  if (file.triangles.size() != object.triangles.size()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "vertex file has " + std::to_string(file.triangles.size()) + " triangles, " +
                         name + " has " + std::to_string(object.triangles.size()));
  }
  for (size_t t = 0; t < file.triangles.size(); ++t) {
    if (file.triangles[t] != object.triangles[t]) {
      return MakeError(ErrorCode::kInvalidArgument, "vertex file's triangle " + std::to_string(t) +
                                                        " differs from " + name +
                                                        "'s (same triangles required)");
    }
  }
  return {};
}

// An object's optional name: a label for people, shown in contact listings and pictures.
Result<void> CheckName(const std::string& name, const std::string& where) {
  if (name.size() > kMaxObjectNameBytes) {
    return Invalid(where + ".name", "longer than " + std::to_string(kMaxObjectNameBytes) +
                                        " bytes (" + std::to_string(name.size()) + ")");
  }
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) {
      return Invalid(where + ".name", "control character (byte " + std::to_string(byte) +
                                          "): names are printed on one line");
    }
  }
  return {};
}

// Meshes of the objects alive at the current frame, by id: vertex files are compared with them.
using MeshesById = std::unordered_map<uint32_t, const Mesh*>;

Result<void> CheckFrame(const FrameUpdate& frame, const std::string& where_frame,
                        SceneModel::Batch& batch, MeshesById& meshes) {
  for (size_t j = 0; j < frame.removals.size(); ++j) {
    if (auto ok = batch.Remove(frame.removals[j]); !ok)
      return AtId(where_frame + ".remove[" + std::to_string(j) + "]", ok.error());
    meshes.erase(frame.removals[j]);
  }
  for (size_t j = 0; j < frame.additions.size(); ++j) {
    const SceneObject& object = frame.additions[j];
    const std::string where = where_frame + ".add[" + std::to_string(j) + "]";
    if (auto ok = batch.Add(object.id, object.mesh, object.motion, object.X_WO); !ok)
      return At(where, ok.error());
    if (auto ok = CheckName(object.name, where); !ok) return ok;
    meshes[object.id] = &object.mesh;
  }
  std::unordered_set<uint32_t> posed;
  for (size_t j = 0; j < frame.poses.size(); ++j) {
    const auto& [id, X_WO] = frame.poses[j];
    const std::string where = where_frame + ".poses[" + std::to_string(j) + "]";
    if (auto ok = batch.SetPose(id, X_WO); !ok) return At(where, ok.error());
    if (!posed.insert(id).second)
      return Invalid(where + ".id",
                     "second pose for object " + std::to_string(id) + " in one frame");
  }
  std::unordered_set<uint32_t> deformed;
  for (size_t j = 0; j < frame.vertices.size(); ++j) {
    const auto& [id, mesh] = frame.vertices[j];
    const std::string where = where_frame + ".vertices[" + std::to_string(j) + "]";
    if (auto ok = batch.SetVertices(id, mesh.p_MV); !ok) return At(where, ok.error());
    if (!deformed.insert(id).second) {
      return Invalid(where + ".id",
                     "second vertex update for object " + std::to_string(id) + " in one frame");
    }
    // A vertex file carries triangles: they must be the object's own, index for index.
    if (auto same = SameTriangles(mesh, *meshes.at(id), id); !same)
      return Invalid(where + ".mesh", same.error().message);
  }
  return {};
}

}  // namespace

Result<void> ValidateScene(const Scene& scene) {
  SceneModel model;
  SceneModel::Batch batch = model.Begin();
  MeshesById meshes;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& object = scene.objects[i];
    const std::string where = "objects[" + std::to_string(i) + "]";
    if (auto ok = batch.Add(object.id, object.mesh, object.motion, object.X_WO); !ok)
      return At(where, ok.error());
    if (auto ok = CheckName(object.name, where); !ok) return ok;
    meshes[object.id] = &object.mesh;
  }
  for (size_t f = 0; f < scene.frames.size(); ++f) {
    if (auto ok = CheckFrame(scene.frames[f], "frames[" + std::to_string(f) + "]", batch, meshes);
        !ok) {
      return ok;
    }
  }
  return {};
}

}  // namespace far
