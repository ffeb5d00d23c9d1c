#pragma once

// How far places an object's vertex in the world: the doubles every exact test reads, and that
// the gpu method's placement kernel must reproduce bit for bit.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

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

/// The world vertex of `p_MV` under `X_WM`: FlushTinyCoordinates of fl(X_WM p_MV), each
/// coordinate summed in this order, one rounding per product and sum: ((r0 x + r1 y) + r2 z) + t.
/// The build turns floating-point contraction off (-ffp-contract=off), so no product is fused
/// into an fma, and the gpu method's placement kernel computes the very same doubles from the
/// same order (`precise`, no fma either). Every stage and reference that places vertices goes
/// through here.
inline Eigen::Vector3d WorldVertex(const Eigen::Matrix<double, 3, 4>& X_WM,
                                   const Eigen::Vector3d& p_MV) {
  Eigen::Vector3d p_WV;
  for (int i = 0; i < 3; ++i) {
    double sum = X_WM(i, 0) * p_MV.x();
    sum = sum + X_WM(i, 1) * p_MV.y();
    sum = sum + X_WM(i, 2) * p_MV.z();
    p_WV[i] = sum + X_WM(i, 3);
  }
  return FlushTinyCoordinates(p_WV);
}
inline Eigen::Vector3d WorldVertex(const Eigen::Isometry3d& X_WM, const Eigen::Vector3d& p_MV) {
  return WorldVertex(X_WM.matrix().topRows<3>(), p_MV);
}

}  // namespace far
