// WriteObj, WritePly and WriteStl: exact (OBJ, PLY) and float32 (STL) mesh writers, used for
// round trips, test fixtures and WriteScene.

#include <cmath>
#include <limits>
#include <string>

#include "io_util.h"
#include <Eigen/Geometry>

#include "far/io/mesh_io.h"

namespace far {
namespace {

// Checks the mesh before writing; names the target in the message.
Result<void> CheckWritable(const Mesh& mesh, const std::filesystem::path& path) {
  Result<void> valid = ValidateMesh(mesh);
  if (valid.ok()) return {};
  return MakeError(valid.error().code,
                   path.string() + ": cannot write mesh: " + valid.error().message);
}

}  // namespace

Result<void> WriteObj(const Mesh& mesh, const std::filesystem::path& path) {
  if (Result<void> status = CheckWritable(mesh, path); !status.ok()) return status;
  std::string text = "# far mesh: " + std::to_string(mesh.p_MV.size()) + " vertices, " +
                     std::to_string(mesh.triangles.size()) + " triangles\n";
  // Shortest round-trip decimals, so ReadObj restores every double exactly.
  for (const Eigen::Vector3d& p_MV : mesh.p_MV) {
    text += "v " + internal::FormatDouble(p_MV.x()) + " " + internal::FormatDouble(p_MV.y()) + " " +
            internal::FormatDouble(p_MV.z()) + "\n";
  }
  for (const TriangleIndices& triangle : mesh.triangles) {
    text += "f " + std::to_string(triangle[0] + 1ull) + " " + std::to_string(triangle[1] + 1ull) +
            " " + std::to_string(triangle[2] + 1ull) + "\n";
  }
  return internal::WriteFileBytes(path, text);
}

Result<void> WritePly(const Mesh& mesh, const std::filesystem::path& path) {
  if (Result<void> status = CheckWritable(mesh, path); !status.ok()) return status;
  std::string bytes = "ply\nformat binary_little_endian 1.0\ncomment written by far\n";
  bytes += "element vertex " + std::to_string(mesh.p_MV.size()) + "\n";
  bytes += "property double x\nproperty double y\nproperty double z\n";
  bytes += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  bytes += "property list uchar uint vertex_indices\nend_header\n";
  bytes.reserve(bytes.size() + 24 * mesh.p_MV.size() + 13 * mesh.triangles.size());
  for (const Eigen::Vector3d& p_MV : mesh.p_MV) {
    for (int axis = 0; axis < 3; ++axis) internal::AppendLittleEndian<double>(p_MV[axis], &bytes);
  }
  for (const TriangleIndices& triangle : mesh.triangles) {
    internal::AppendLittleEndian<uint8_t>(3, &bytes);
    for (const uint32_t index : triangle) internal::AppendLittleEndian<uint32_t>(index, &bytes);
  }
  return internal::WriteFileBytes(path, bytes);
}

Result<void> WriteStl(const Mesh& mesh, const std::filesystem::path& path) {
  if (Result<void> status = CheckWritable(mesh, path); !status.ok()) return status;
  // STL stores float32: refuse coordinates that would become infinite.
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  for (size_t v = 0; v < mesh.p_MV.size(); ++v) {
    if (mesh.p_MV[v].cwiseAbs().maxCoeff() > kFloatMax) {
      return MakeError(ErrorCode::kInvalidArgument, path.string() + ": cannot write mesh: vertex " +
                                                        std::to_string(v) +
                                                        " does not fit in float32 (STL)");
    }
  }
  std::string bytes(80, ' ');
  bytes.replace(0, 18, "binary STL by far ");
  internal::AppendLittleEndian<uint32_t>(static_cast<uint32_t>(mesh.triangles.size()), &bytes);
  bytes.reserve(bytes.size() + 50 * mesh.triangles.size());
  for (const TriangleIndices& triangle : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.p_MV[triangle[0]];
    const Eigen::Vector3d& b = mesh.p_MV[triangle[1]];
    const Eigen::Vector3d& c = mesh.p_MV[triangle[2]];
    // The unit normal, or zero for a degenerate triangle.
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double norm = cross.norm();
    const Eigen::Vector3d normal =
        norm > 0 && std::isfinite(norm) ? Eigen::Vector3d(cross / norm) : Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d* p : {&normal, &a, &b, &c}) {
      for (int axis = 0; axis < 3; ++axis) {
        internal::AppendLittleEndian<float>(static_cast<float>((*p)[axis]), &bytes);
      }
    }
    internal::AppendLittleEndian<uint16_t>(0, &bytes);
  }
  return internal::WriteFileBytes(path, bytes);
}

}  // namespace far
