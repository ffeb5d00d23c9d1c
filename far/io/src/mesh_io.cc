// ReadMesh and WriteMesh: dispatch on the file extension.

#include "far/io/mesh_io.h"

#include <cmath>
#include <string>

#include "io_util.h"

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

}  // namespace far
