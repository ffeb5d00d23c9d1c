// ValidateMesh: what every mesh must satisfy, whatever it came from.

#include "far/model/mesh.h"

#include <string>

#include "far/base/limits.h"

namespace far {

Result<void> ValidateMesh(const Mesh& mesh) {
  if (mesh.triangles.empty()) return MakeError(ErrorCode::kInvalidArgument, "no triangles");
  if (mesh.p_MV.size() > kMaxMeshElements || mesh.triangles.size() > kMaxMeshElements) {
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
