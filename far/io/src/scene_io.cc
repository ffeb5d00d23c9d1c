// far-scene/1 reader and writer. The JSON shape is checked here, with the JSON path of every
// bad value in the message; the meaning (ids, motions, frame bookkeeping) by ValidateScene.

#include "far/io/scene_io.h"

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <unordered_set>
#include <vector>

#include "io_util.h"
#include "known_keys.h"
#include <nlohmann/json.hpp>

#include "far/io/mesh_io.h"

namespace far {
namespace {

using Json = nlohmann::json;

constexpr std::string_view kFormat = "far-scene/1";
constexpr std::string_view kFormatPrefix = "far-scene/";

// Errors in the JSON's shape (missing keys, wrong types) and in its values.
Error ShapeError(const std::string& where, const std::string& what) {
  return MakeError(ErrorCode::kParseError, where + ": " + what);
}
Error ValueError(const std::string& where, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument, where + ": " + what);
}

std::string Index(const std::string& where, size_t i) {
  return where + "[" + std::to_string(i) + "]";
}

// Parses JSON text; rejects syntax errors (with the byte offset) and duplicate keys.
Result<Json> ParseJson(std::string_view text) {
  std::vector<std::unordered_set<std::string>> keys;  // one set per open JSON object
  std::string duplicate;
  const Json::parser_callback_t check_keys = [&](int /*depth*/, Json::parse_event_t event,
                                                 Json& parsed) {
    if (event == Json::parse_event_t::object_start) {
      keys.emplace_back();
    } else if (event == Json::parse_event_t::object_end) {
      keys.pop_back();
    } else if (event == Json::parse_event_t::key && !keys.empty()) {
      if (!keys.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
        duplicate = parsed.get<std::string>();
      }
    }
    return true;
  };
  Json json;
  try {
    json = Json::parse(text.begin(), text.end(), check_keys);
  } catch (const Json::parse_error& e) {
    // nlohmann counts bytes from 1; our messages give 0-based offsets, as the mesh readers do.
    const size_t offset = e.byte > 0 ? e.byte - 1 : 0;
    return MakeError(ErrorCode::kParseError,
                     "JSON syntax error at byte " + std::to_string(offset) + ": " + e.what());
  } catch (const Json::exception& e) {
    return MakeError(ErrorCode::kParseError, std::string("JSON error: ") + e.what());
  }
  if (!duplicate.empty()) {
    return MakeError(ErrorCode::kParseError,
                     "duplicate key \"" + duplicate + "\" in a JSON object (keys must be unique)");
  }
  return json;
}

// Returns the member `key` of the JSON object `object`, or nullptr.
const Json* Find(const Json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

Result<const Json*> Require(const Json& object, const char* key, const std::string& where) {
  const Json* member = Find(object, key);
  if (member == nullptr) return ShapeError(where, "missing");
  return member;
}

Result<void> ExpectObject(const Json& json, const std::string& where) {
  if (json.is_object()) return {};
  return ShapeError(where, std::string("expected a JSON object, got ") + json.type_name());
}

Result<void> ExpectArray(const Json& json, const std::string& where) {
  if (json.is_array()) return {};
  return ShapeError(where, std::string("expected an array, got ") + json.type_name());
}

// The keys of each JSON object level of far-scene/1. Every level may carry a "comment" string.
template <size_t N>
using Keys = std::array<std::string_view, N>;
constexpr Keys<4> kRootKeys = {"format", "objects", "frames", "comment"};
constexpr Keys<6> kObjectKeys = {"id", "name", "mesh", "motion", "pose", "comment"};
constexpr Keys<3> kPoseKeys = {"translation", "rotation_wxyz", "comment"};
constexpr Keys<5> kFrameKeys = {"remove", "add", "poses", "vertices", "comment"};
constexpr Keys<4> kFramePoseKeys = {"id", "translation", "rotation_wxyz", "comment"};
constexpr Keys<3> kVertexKeys = {"id", "mesh", "comment"};

// Checks the JSON object `json` at `where` (`what` names the level in messages): every key
// known, and "comment", when present, a string.
Result<void> CheckLevel(const Json& json, const std::string& where, const char* what,
                        std::span<const std::string_view> known) {
  if (Result<void> keys = internal::CheckKnownKeys(json, where, what, known); !keys.ok()) {
    return keys;
  }
  if (const auto comment = json.find("comment"); comment != json.end() && !comment->is_string()) {
    return ShapeError((where == "(root)" ? "" : where + ".") + "comment",
                      std::string("expected a string, got ") + comment->type_name());
  }
  return {};
}

Result<uint32_t> ParseId(const Json& json, const std::string& where) {
  if (json.is_number_unsigned() && json.get<uint64_t>() <= std::numeric_limits<uint32_t>::max()) {
    return static_cast<uint32_t>(json.get<uint64_t>());
  }
  if (json.is_number()) {
    return ValueError(where, "expected an unsigned 32-bit integer, got " + json.dump());
  }
  return ShapeError(where,
                    std::string("expected an unsigned 32-bit integer, got ") + json.type_name());
}

Result<double> ParseNumber(const Json& json, const std::string& where) {
  if (!json.is_number()) {
    return ShapeError(where, std::string("expected a number, got ") + json.type_name());
  }
  const double value = json.get<double>();
  if (!std::isfinite(value)) return ValueError(where, "not finite");
  return value;
}

// An array of exactly N finite numbers.
template <int N>
Result<Eigen::Matrix<double, N, 1>> ParseVector(const Json& json, const std::string& where) {
  if (!json.is_array() || json.size() != N) {
    return ShapeError(where, "expected an array of " + std::to_string(N) + " numbers, got " +
                                 (json.is_array() ? std::to_string(json.size()) + " values"
                                                  : std::string(json.type_name())));
  }
  Eigen::Matrix<double, N, 1> values;
  for (int i = 0; i < N; ++i) {
    const Result<double> value = ParseNumber(json[i], Index(where, i));
    if (!value.ok()) return value.error();
    values[i] = *value;
  }
  return values;
}

// Reads the optional translation and rotation_wxyz of the JSON object `json` at `where`.
Result<Pose> ParsePose(const Json& json, const std::string& where) {
  Pose pose;
  if (const Json* translation = Find(json, "translation")) {
    const Result<Eigen::Vector3d> p = ParseVector<3>(*translation, where + ".translation");
    if (!p.ok()) return p.error();
    pose.translation = *p;
  }
  if (const Json* rotation = Find(json, "rotation_wxyz")) {
    const std::string where_rotation = where + ".rotation_wxyz";
    const Result<Eigen::Vector4d> wxyz = ParseVector<4>(*rotation, where_rotation);
    if (!wxyz.ok()) return wxyz.error();
    pose.rotation = Eigen::Quaterniond((*wxyz)[0], (*wxyz)[1], (*wxyz)[2], (*wxyz)[3]);
  }
  // The model's rule (kQuaternionTolerance), then normalized: the daemon and the pipeline see
  // the exact rotation the file's rounded numbers stand for.
  Result<Pose> unit = CheckAndNormalizePose(pose);
  if (!unit.ok()) return MakeError(unit.error().code, where + "." + unit.error().message);
  return *unit;
}

// Builds a Scene from the JSON tree, loading mesh files relative to the scene's folder.
class SceneParser {
 public:
  explicit SceneParser(std::filesystem::path base_dir) : base_dir_(std::move(base_dir)) {}

  Result<Scene> Parse(const Json& root) {
    if (Result<void> status = ExpectObject(root, "(root)"); !status.ok()) return status.error();
    // The format string first: a different version is a different error.
    const Result<const Json*> format = Require(root, "format", "format");
    if (!format.ok()) return format.error();
    if (!(*format)->is_string()) {
      return ShapeError("format", std::string("expected a string, got ") + (*format)->type_name());
    }
    const std::string format_text = (*format)->get<std::string>();
    if (format_text != kFormat) {
      if (format_text.starts_with(kFormatPrefix)) {
        return MakeError(ErrorCode::kVersionMismatch, "format: unsupported version \"" +
                                                          format_text + "\" (this reader reads \"" +
                                                          std::string(kFormat) + "\")");
      }
      return ShapeError("format", "expected \"" + std::string(kFormat) + "\", got " +
                                      internal::Quote(format_text));
    }
    // The format is known now: every other key must be one of far-scene/1's.
    if (Result<void> keys = CheckLevel(root, "(root)", "the top level", kRootKeys); !keys.ok()) {
      return keys.error();
    }
    // Objects, then frames.
    Scene scene;
    const Result<const Json*> objects = Require(root, "objects", "objects");
    if (!objects.ok()) return objects.error();
    if (Result<void> status = ExpectArray(**objects, "objects"); !status.ok()) {
      return status.error();
    }
    for (size_t i = 0; i < (*objects)->size(); ++i) {
      Result<SceneObject> object = ParseObject((**objects)[i], Index("objects", i));
      if (!object.ok()) return object.error();
      scene.objects.push_back(std::move(*object));
    }
    if (const Json* frames = Find(root, "frames")) {
      if (Result<void> status = ExpectArray(*frames, "frames"); !status.ok()) return status.error();
      for (size_t f = 0; f < frames->size(); ++f) {
        Result<FrameUpdate> frame = ParseFrame((*frames)[f], Index("frames", f));
        if (!frame.ok()) return frame.error();
        scene.frames.push_back(std::move(*frame));
      }
    }
    // Then the meaning: ids, motions, bookkeeping across frames.
    if (Result<void> status = ValidateScene(scene); !status.ok()) return status.error();
    return scene;
  }

 private:
  // Reads the mesh file named by the string at `where`; errors name the object.
  Result<Mesh> LoadMesh(const Json& json, const std::string& where, uint32_t id,
                        std::string* mesh_path) {
    if (!json.is_string()) {
      return ShapeError(where, std::string("expected a file path string, got ") + json.type_name());
    }
    *mesh_path = json.get<std::string>();
    if (mesh_path->empty()) return ValueError(where, "empty path");
    const std::filesystem::path relative(*mesh_path);
    if (relative.is_absolute()) {
      return ValueError(
          where, internal::Quote(*mesh_path, 200) + " must be relative to the scene file's folder");
    }
    const std::filesystem::path full = (base_dir_ / relative).lexically_normal();
    if (const auto it = cache_.find(full); it != cache_.end()) return it->second;
    Result<Mesh> mesh = ReadMesh(full);
    if (!mesh.ok()) {
      return MakeError(mesh.error().code,
                       where + ": object " + std::to_string(id) + ": " + mesh.error().message);
    }
    cache_.emplace(full, *mesh);
    return mesh;
  }

  // {"id": 7, "mesh": "leaf.obj", "motion": "rigid", "pose": {...}}
  Result<SceneObject> ParseObject(const Json& json, const std::string& where) {
    if (Result<void> status = ExpectObject(json, where); !status.ok()) return status.error();
    if (Result<void> keys = CheckLevel(json, where, "an object", kObjectKeys); !keys.ok()) {
      return keys.error();
    }
    SceneObject object;
    // id, motion and pose first: cheap, and they name the object in mesh errors.
    const Result<const Json*> id = Require(json, "id", where + ".id");
    if (!id.ok()) return id.error();
    const Result<uint32_t> id_value = ParseId(**id, where + ".id");
    if (!id_value.ok()) return id_value.error();
    object.id = *id_value;
    const Result<const Json*> motion = Require(json, "motion", where + ".motion");
    if (!motion.ok()) return motion.error();
    if (!(*motion)->is_string()) {
      return ShapeError(where + ".motion",
                        std::string("expected a string, got ") + (*motion)->type_name());
    }
    const std::optional<Motion> motion_value = ParseMotion((*motion)->get<std::string>());
    if (!motion_value) {
      return ValueError(where + ".motion", "unknown motion " +
                                               internal::Quote((*motion)->get<std::string>()) +
                                               " (expected static, rigid or deformable)");
    }
    object.motion = *motion_value;
    if (const Json* name = Find(json, "name")) {
      if (!name->is_string()) {
        return ShapeError(where + ".name",
                          std::string("expected a string, got ") + name->type_name());
      }
      object.name = name->get<std::string>();  // its content is ValidateScene's to check
    }
    if (const Json* pose = Find(json, "pose")) {
      if (Result<void> status = ExpectObject(*pose, where + ".pose"); !status.ok()) {
        return status.error();
      }
      if (Result<void> keys = CheckLevel(*pose, where + ".pose", "a pose", kPoseKeys); !keys.ok()) {
        return keys.error();
      }
      Result<Pose> X_WO = ParsePose(*pose, where + ".pose");
      if (!X_WO.ok()) return X_WO.error();
      object.X_WO = *X_WO;
    }
    const Result<const Json*> mesh = Require(json, "mesh", where + ".mesh");
    if (!mesh.ok()) return mesh.error();
    Result<Mesh> mesh_value = LoadMesh(**mesh, where + ".mesh", object.id, &object.mesh_path);
    if (!mesh_value.ok()) return mesh_value.error();
    object.mesh = std::move(*mesh_value);
    return object;
  }

  // {"remove": [4], "add": [<object>], "poses": [{"id": 3, ...}], "vertices": [{"id": 5, "mesh":
  // ...}]}
  Result<FrameUpdate> ParseFrame(const Json& json, const std::string& where) {
    if (Result<void> status = ExpectObject(json, where); !status.ok()) return status.error();
    if (Result<void> keys = CheckLevel(json, where, "a frame", kFrameKeys); !keys.ok()) {
      return keys.error();
    }
    FrameUpdate frame;
    if (const Json* remove = Find(json, "remove")) {
      if (Result<void> status = ExpectArray(*remove, where + ".remove"); !status.ok()) {
        return status.error();
      }
      for (size_t j = 0; j < remove->size(); ++j) {
        const Result<uint32_t> id = ParseId((*remove)[j], Index(where + ".remove", j));
        if (!id.ok()) return id.error();
        frame.removals.push_back(*id);
      }
    }
    if (const Json* add = Find(json, "add")) {
      if (Result<void> status = ExpectArray(*add, where + ".add"); !status.ok()) {
        return status.error();
      }
      for (size_t j = 0; j < add->size(); ++j) {
        Result<SceneObject> object = ParseObject((*add)[j], Index(where + ".add", j));
        if (!object.ok()) return object.error();
        frame.additions.push_back(std::move(*object));
      }
    }
    if (const Json* poses = Find(json, "poses")) {
      if (Result<void> status = ParseFramePoses(*poses, where + ".poses", &frame); !status.ok()) {
        return status.error();
      }
    }
    if (const Json* vertices = Find(json, "vertices")) {
      if (Result<void> status = ParseFrameVertices(*vertices, where + ".vertices", &frame);
          !status.ok()) {
        return status.error();
      }
    }
    return frame;
  }

  // [{"id": 3, "translation": [...], "rotation_wxyz": [...]}, ...] into frame->poses.
  static Result<void> ParseFramePoses(const Json& poses, const std::string& where,
                                      FrameUpdate* frame) {
    if (Result<void> status = ExpectArray(poses, where); !status.ok()) return status;
    for (size_t j = 0; j < poses.size(); ++j) {
      const std::string where_pose = Index(where, j);
      const Json& entry = poses[j];
      if (Result<void> status = ExpectObject(entry, where_pose); !status.ok()) return status;
      if (Result<void> keys = CheckLevel(entry, where_pose, "a frame's pose", kFramePoseKeys);
          !keys.ok()) {
        return keys;
      }
      const Result<const Json*> id = Require(entry, "id", where_pose + ".id");
      if (!id.ok()) return id.error();
      const Result<uint32_t> id_value = ParseId(**id, where_pose + ".id");
      if (!id_value.ok()) return id_value.error();
      Result<Pose> X_WO = ParsePose(entry, where_pose);
      if (!X_WO.ok()) return X_WO.error();
      frame->poses.emplace_back(*id_value, *X_WO);
    }
    return {};
  }

  // [{"id": 5, "mesh": "leaf_t1.obj"}, ...] into frame->vertices and frame->vertex_mesh_paths.
  Result<void> ParseFrameVertices(const Json& vertices, const std::string& where,
                                  FrameUpdate* frame) {
    if (Result<void> status = ExpectArray(vertices, where); !status.ok()) return status;
    for (size_t j = 0; j < vertices.size(); ++j) {
      const std::string where_vertices = Index(where, j);
      const Json& entry = vertices[j];
      if (Result<void> status = ExpectObject(entry, where_vertices); !status.ok()) return status;
      if (Result<void> keys =
              CheckLevel(entry, where_vertices, "a frame's vertices entry", kVertexKeys);
          !keys.ok()) {
        return keys;
      }
      const Result<const Json*> id = Require(entry, "id", where_vertices + ".id");
      if (!id.ok()) return id.error();
      const Result<uint32_t> id_value = ParseId(**id, where_vertices + ".id");
      if (!id_value.ok()) return id_value.error();
      const Result<const Json*> mesh = Require(entry, "mesh", where_vertices + ".mesh");
      if (!mesh.ok()) return mesh.error();
      std::string mesh_path;
      Result<Mesh> mesh_value = LoadMesh(**mesh, where_vertices + ".mesh", *id_value, &mesh_path);
      if (!mesh_value.ok()) return mesh_value.error();
      frame->vertices.emplace_back(*id_value, std::move(*mesh_value));
      frame->vertex_mesh_paths.push_back(std::move(mesh_path));
    }
    return {};
  }

  std::filesystem::path base_dir_;
  std::map<std::filesystem::path, Mesh> cache_;  // meshes already read, by normalized path
};

Json PoseToJson(const Pose& pose) {
  const Eigen::Quaterniond& q = pose.rotation;
  return Json{{"translation", {pose.translation.x(), pose.translation.y(), pose.translation.z()}},
              {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

Json ObjectToJson(const SceneObject& object) {
  Json json = {{"id", object.id},
               {"mesh", object.mesh_path},
               {"motion", ToString(object.motion)},
               {"pose", PoseToJson(object.X_WO)}};
  if (!object.name.empty()) json["name"] = object.name;
  return json;
}

bool SameMesh(const Mesh& a, const Mesh& b) {
  return a.triangles == b.triangles && a.p_MV.size() == b.p_MV.size() &&
         std::equal(a.p_MV.begin(), a.p_MV.end(), b.p_MV.begin(),
                    [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return p == q; });
}

// Writes each referenced mesh that has no file yet, once per path.
class MeshFileWriter {
 public:
  explicit MeshFileWriter(std::filesystem::path scene_dir) : scene_dir_(std::move(scene_dir)) {}

  Result<void> Ensure(const std::string& mesh_path, const Mesh& mesh, const std::string& where) {
    if (mesh_path.empty()) return ValueError(where, "empty mesh path");
    const std::filesystem::path relative(mesh_path);
    if (relative.is_absolute()) {
      return ValueError(
          where, internal::Quote(mesh_path, 200) + " must be relative to the scene file's folder");
    }
    const std::filesystem::path full = (scene_dir_ / relative).lexically_normal();
    // The same path twice in one scene must mean the same mesh.
    if (const auto it = seen_.find(full); it != seen_.end()) {
      if (!SameMesh(*it->second.mesh, mesh)) {
        return ValueError(where, internal::Quote(mesh_path, 200) + " is also used by " +
                                     it->second.where + " with a different mesh");
      }
      return {};
    }
    seen_.emplace(full, Seen{&mesh, where});
    std::error_code ec;
    if (std::filesystem::exists(full, ec)) return {};
    if (full.has_parent_path()) std::filesystem::create_directories(full.parent_path(), ec);
    Result<void> written = WriteMesh(mesh, full);
    if (!written.ok()) {
      return MakeError(written.error().code, where + ": " + written.error().message);
    }
    return {};
  }

 private:
  struct Seen {
    const Mesh* mesh;
    std::string where;
  };
  std::filesystem::path scene_dir_;
  std::map<std::filesystem::path, Seen> seen_;
};

}  // namespace

Result<Scene> ParseScene(std::string_view json, const std::filesystem::path& base_dir) {
  Result<Json> root = ParseJson(json);
  if (!root.ok()) return root.error();
  return SceneParser(base_dir).Parse(*root);
}

Result<Scene> ReadScene(const std::filesystem::path& path) {
  Result<std::string> bytes = internal::ReadFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  Result<Scene> scene = ParseScene(*bytes, path.parent_path());
  if (!scene.ok()) {
    return MakeError(scene.error().code, path.string() + ": " + scene.error().message);
  }
  return scene;
}

Result<void> WriteScene(const Scene& scene, const std::filesystem::path& scene_path) {
  // Check everything before writing anything.
  if (Result<void> status = ValidateScene(scene); !status.ok()) return status;
  const std::filesystem::path scene_dir = scene_path.parent_path();
  MeshFileWriter meshes(scene_dir);
  Json root = {{"format", kFormat}, {"objects", Json::array()}};
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& object = scene.objects[i];
    const std::string where = Index("objects", i) + ".mesh";
    if (Result<void> status = meshes.Ensure(object.mesh_path, object.mesh, where); !status.ok()) {
      return status;
    }
    root["objects"].push_back(ObjectToJson(object));
  }
  if (!scene.frames.empty()) root["frames"] = Json::array();
  for (size_t f = 0; f < scene.frames.size(); ++f) {
    const FrameUpdate& frame = scene.frames[f];
    const std::string where = Index("frames", f);
    Json frame_json = Json::object();
    if (!frame.removals.empty()) frame_json["remove"] = frame.removals;
    for (size_t j = 0; j < frame.additions.size(); ++j) {
      const SceneObject& object = frame.additions[j];
      const std::string where_mesh = Index(where + ".add", j) + ".mesh";
      if (Result<void> status = meshes.Ensure(object.mesh_path, object.mesh, where_mesh);
          !status.ok()) {
        return status;
      }
      frame_json["add"].push_back(ObjectToJson(object));
    }
    for (const auto& [id, X_WO] : frame.poses) {
      Json pose = PoseToJson(X_WO);
      pose["id"] = id;
      frame_json["poses"].push_back(std::move(pose));
    }
    const bool have_paths = frame.vertex_mesh_paths.size() == frame.vertices.size();
    for (size_t j = 0; j < frame.vertices.size(); ++j) {
      const auto& [id, mesh] = frame.vertices[j];
      std::string mesh_path = have_paths ? frame.vertex_mesh_paths[j] : std::string();
      if (mesh_path.empty()) {
        mesh_path = scene_path.stem().string() + "_frame" + std::to_string(f) + "_id" +
                    std::to_string(id) + ".obj";
      }
      const std::string where_mesh = Index(where + ".vertices", j) + ".mesh";
      if (Result<void> status = meshes.Ensure(mesh_path, mesh, where_mesh); !status.ok()) {
        return status;
      }
      frame_json["vertices"].push_back(Json{{"id", id}, {"mesh", mesh_path}});
    }
    root["frames"].push_back(std::move(frame_json));
  }
  if (!scene_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(scene_dir, ec);
  }
  return internal::WriteFileBytes(scene_path, root.dump(2) + "\n");
}

}  // namespace far
