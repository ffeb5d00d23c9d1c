#pragma once

// The probe on which ComputeCollider checks, once per device, that its placement kernel computes
// far::WorldVertex's doubles: posed vertices whose sums round differently under an fma or
// another order of the terms, so that a device that fused or reordered them would show it.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace far::internal {

/// kVertices vertices per pose, each pose with its own scale, so that the terms of each sum are
/// comparable: scales from 2^-258 (products near the flush, kTinyWorldCoordinate) to 2^39
/// (about far::kMaxCoordinate), and every other pose's last vertex mapped near the origin,
/// where the sums cancel.
struct PlacementProbe {
  static constexpr size_t kPoses = 8, kVertices = 64;
  std::vector<Eigen::Vector3d> p_MV;              ///< pose k's: [k kVertices, (k + 1) kVertices)
  std::vector<Eigen::Matrix<double, 3, 4>> X_WM;  ///< by pose
};

/// The same probe every time (a fixed seed).
PlacementProbe MakePlacementProbe();

}  // namespace far::internal
