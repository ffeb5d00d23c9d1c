#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "far/model/mesh.h"
#include "far/model/world_vertex.h"  // kTinyWorldCoordinate, WorldVertex

namespace far {

/// A read-only view of one object placed in the world: its world-frame vertex positions and its
/// triangles. The stages take views in a span indexed by slot (far/model/object_slot.h); a free
/// slot's view is empty. Aliased: the spans must outlive the view.
struct WorldObjectView {
  std::span<const Eigen::Vector3d> p_WV;  ///< vertex positions in world frame W
  std::span<const TriangleIndices> triangles;
};

}  // namespace far
