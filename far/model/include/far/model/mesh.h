#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "far/base/result.h"

namespace far {

/// Three vertex indices of a triangle, counter-clockwise seen from the front.
using TriangleIndices = std::array<uint32_t, 3>;

/// A triangle mesh: double positions in the mesh's own frame M and uint32 triangles.
/// Triangle index t is the t-th triangle of the file it came from (polygons fan-triangulated in
/// file order). Every index is < positions.size() once a reader or validator has accepted it.
struct Mesh {
  std::vector<Eigen::Vector3d> p_MV;  ///< vertex positions in frame M
  std::vector<TriangleIndices> triangles;

  int num_vertices() const { return static_cast<int>(p_MV.size()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
};

/// Checks that `mesh` has at least one triangle, at most kMaxMeshElements vertices and
/// triangles, finite positions and in-range indices. Errors: kInvalidArgument naming the first
/// bad vertex or triangle, kLimitExceeded for too many elements.
Result<void> ValidateMesh(const Mesh& mesh);

}  // namespace far
