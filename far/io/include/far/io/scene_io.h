#pragma once

// Reading and writing `far-scene/1` scene files (JSON). The format, its validation rules and
// its error codes are documented in docs/scene-format.md.
//
// Thread safety: all functions are reentrant; they share no state.

#include <filesystem>
#include <string_view>

#include "far/base/result.h"
#include "far/model/scene.h"

namespace far {

/// Reads the scene file at `path` and every mesh and vertex file it names (paths relative to
/// the scene file's folder). Errors: kIoError when the scene file cannot be read; otherwise as
/// ParseScene, with the scene file's path in front of the message.
Result<Scene> ReadScene(const std::filesystem::path& path);

/// Parses scene JSON held in memory, loading mesh files relative to `base_dir`, then checks it
/// with ValidateScene. Errors name the JSON path of the bad value, e.g.
/// "objects[2].pose.rotation_wxyz: not a unit quaternion (norm 1.7): ...":
///  - kParseError: JSON syntax (with the byte offset), wrong types, missing fields, unknown keys,
///    wrong format;
///  - kVersionMismatch: a format string "far-scene/N" other than "far-scene/1";
///  - kInvalidArgument: bad values (ids, motion names, non-unit quaternions, duplicate ids, ...);
///  - kNotFound: frames naming ids that are not alive at that point;
///  - the mesh reader's code (kIoError, kParseError, ...) for mesh files, with the object named.
/// Every key is checked: an unknown key is a kParseError naming it, its JSON path and the
/// closest known key ("objects[0].pose.translaton: unknown key 'translaton'; did you mean
/// 'translation'? ..."); "comment" (a string) is allowed everywhere. Duplicate keys in one JSON
/// object are an error. Quaternions within kQuaternionTolerance (1e-3) of unit norm are
/// accepted and normalized.
Result<Scene> ParseScene(std::string_view json, const std::filesystem::path& base_dir);

/// Writes `scene` as `far-scene/1` JSON to `scene_path`. Each mesh is referenced by its
/// mesh_path; when no file exists at that path (relative to the scene file's folder) the mesh is
/// written there in the format of its extension (folders created as needed); an existing file
/// is left alone and trusted to hold that mesh. Vertex updates without a path get
/// "<scene stem>_frame<k>_id<id>.obj". Errors: what ValidateScene returns (the scene is checked
/// before anything is written), kInvalidArgument for an empty or absolute mesh_path, kIoError
/// when a file cannot be written.
Result<void> WriteScene(const Scene& scene, const std::filesystem::path& scene_path);

}  // namespace far
