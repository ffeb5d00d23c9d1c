#pragma once

#include <cmath>
#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "far/model/mesh.h"

namespace far {

/// World coordinates whose magnitude is below this (2^-256, about 8.6e-78) are taken as 0. The
/// exact predicates are exact only where no product underflows (far/geometry's predicates.h:
/// nonzero coordinates of at least 2^-300, nonzero differences of at least 2^-330). A rotation
/// can turn a coordinate of any size into a tiny one (R p + t cancels, or R has tiny entries),
/// and below that range they judge crossing pairs apart or apart pairs crossing. With every
/// nonzero world coordinate in [2^-256, 3e12] (far::kMaxCoordinate bounds the top), nonzero
/// differences are at least 2^-308: inside the range. Moving a point by less than 2^-256 changes
/// no answer that a scene in any physical unit can notice.
inline constexpr double kTinyWorldCoordinate = 0x1p-256;

/// `p` with every coordinate of magnitude below kTinyWorldCoordinate set to 0: how the pipeline
/// turns X_WM p_MV into the world vertices every exact test reads.
inline Eigen::Vector3d FlushTinyCoordinates(Eigen::Vector3d p) {
  for (int k = 0; k < 3; ++k) p[k] = std::abs(p[k]) < kTinyWorldCoordinate ? 0.0 : p[k];
  return p;
}

/// A read-only view of one object placed in the world: its world-frame vertex positions and its
/// triangles. The stages take views in a span indexed by slot (far/model/object_slot.h); a free
/// slot's view is empty. Aliased: the spans must outlive the view.
struct WorldObjectView {
  std::span<const Eigen::Vector3d> p_WV;  ///< vertex positions in world frame W
  std::span<const TriangleIndices> triangles;
};

}  // namespace far
