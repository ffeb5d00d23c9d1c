// ReadMesh and WriteMesh: dispatch on the file extension; ValidateMesh.

#include "far/mesh_io.h"

#include <cmath>
#include <string>

#include "io/io_util.h"

namespace far {
namespace {

enum class MeshFormat { kObj, kPly, kStl, kUnknown };

MeshFormat FormatOf(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  if (extension == ".obj") return MeshFormat::kObj;
  if (extension == ".ply") return MeshFormat::kPly;
  if (extension == ".stl") return MeshFormat::kStl;
  return MeshFormat::kUnknown;
}

Error UnknownExtension(const std::filesystem::path& path) {
  return MakeError(ErrorCode::kInvalidArgument, path.string() + ": unknown mesh file extension " +
                                                    internal::Quote(path.extension().string()) +
                                                    " (expected .obj, .ply or .stl)");
}

}  // namespace

Result<Mesh> ReadMesh(const std::filesystem::path& path) {
  switch (FormatOf(path)) {
    case MeshFormat::kObj:
      return ReadObj(path);
    case MeshFormat::kPly:
      return ReadPly(path);
    case MeshFormat::kStl:
      return ReadStl(path);
    case MeshFormat::kUnknown:
      break;
  }
  return UnknownExtension(path);
}

Result<void> WriteMesh(const Mesh& mesh, const std::filesystem::path& path) {
  switch (FormatOf(path)) {
    case MeshFormat::kObj:
      return WriteObj(mesh, path);
    case MeshFormat::kPly:
      return WritePly(mesh, path);
    case MeshFormat::kStl:
      return WriteStl(mesh, path);
    case MeshFormat::kUnknown:
      break;
  }
  return UnknownExtension(path);
}

Result<void> ValidateMesh(const Mesh& mesh) {
  if (mesh.triangles.empty()) return MakeError(ErrorCode::kInvalidArgument, "no triangles");
  if (mesh.p_MV.size() > internal::kMaxMeshElements ||
      mesh.triangles.size() > internal::kMaxMeshElements) {
    return MakeError(ErrorCode::kLimitExceeded, "more than 2^31-1 vertices or triangles");
  }
  for (size_t v = 0; v < mesh.p_MV.size(); ++v) {
    if (!mesh.p_MV[v].allFinite()) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const uint32_t index : mesh.triangles[t]) {
      if (index >= mesh.p_MV.size()) {
        return MakeError(ErrorCode::kInvalidArgument,
                         "triangle " + std::to_string(t) + ": vertex index " +
                             std::to_string(index) + " out of range (" +
                             std::to_string(mesh.p_MV.size()) + " vertices)");
      }
    }
  }
  return {};
}

}  // namespace far
