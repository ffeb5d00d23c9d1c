#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "far/model/mesh.h"

namespace far {

/// A read-only view of one object placed in the world: its id, its world-frame vertex
/// positions and its triangles. Aliased: the spans must outlive the view.
struct WorldObjectView {
  uint32_t id = 0;
  std::span<const Eigen::Vector3d> p_WV;  ///< vertex positions in world frame W
  std::span<const TriangleIndices> triangles;
};

}  // namespace far
