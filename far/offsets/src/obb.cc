// Oriented boxes: growth, rigid motion, world AABB, corners and their triangles.

#include <cmath>

#include "triangle_frame.h"

#include "far/offsets/bounding_offset.h"

namespace far {

Obb GrowObb(const Obb& box, double r) {
  Obb grown = box;
  for (int i = 0; i < 3; ++i) grown.half_extents[i] = internal::RoundUp(box.half_extents[i] + r);
  return grown;
}

Obb TransformObb(const Eigen::Isometry3d& X_WM, const Obb& box_M) {
  Obb box_W;
  box_W.center = X_WM * box_M.center;
  box_W.axes = X_WM.linear() * box_M.axes;
  box_W.half_extents = box_M.half_extents;
  return box_W;
}

Eigen::AlignedBox3d ObbAabb(const Obb& box) {
  // Half widths along the world axes, rounded outward by more than the rounding of the sum
  // and of a caller's corner computation (center + sum of three terms).
  const Eigen::Vector3d reach = box.axes.cwiseAbs() * box.half_extents;
  const Eigen::Vector3d pad =
      16 * internal::kDoubleUnit * (box.center.cwiseAbs() + reach) + internal::kInflation * reach;
  return Eigen::AlignedBox3d(box.center - reach - pad, box.center + reach + pad);
}

std::array<Eigen::Vector3d, 8> ObbCorners(const Obb& box) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d corner = box.center;
    for (int i = 0; i < 3; ++i) {
      const double s = ((k >> i) & 1) ? 1.0 : -1.0;
      corner += s * box.half_extents[i] * box.axes.col(i);
    }
    corners[k] = corner;
  }
  return corners;
}

// Two triangles per face; corner k has bit i set on the +axis i side. Each triangle's normal
// (p1 - p0) x (p2 - p0) points along the face's outward axis for right-handed axes.
const std::array<uint8_t, 36> kBoxTriangleCorners = {
    0, 4, 6, 0, 6, 2,  // -x
    1, 3, 7, 1, 7, 5,  // +x
    0, 1, 5, 0, 5, 4,  // -y
    2, 6, 7, 2, 7, 3,  // +y
    0, 2, 3, 0, 3, 1,  // -z
    4, 5, 7, 4, 7, 6,  // +z
};

}  // namespace far
