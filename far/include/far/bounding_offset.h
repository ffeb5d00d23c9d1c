#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace far {

/// Depth buffer formats a culling pass can render with.
enum class DepthFormat { kDepth16, kDepth24, kDepth32F };

/// Returns RES(Z), the number of distinguishable depth steps over [0, 1] (2^16, 2^24, 2^24).
double DepthResolution(DepthFormat format);

/// The framebuffer a culling pass renders into: viewport RES(X) x RES(Y) and RES(Z).
struct RasterFormat {
  int width = 1024;
  int height = 1024;
  DepthFormat depth = DepthFormat::kDepth24;
};

/// The orthographic set-up shared by the three axis views of one culling pass.
struct Projection {
  Eigen::AlignedBox3d bounds_W;  ///< contains every fattened primitive, strictly
  Eigen::Vector3d center_W;      ///< subtracted in double before coordinates become float32
  double radius = 0;             ///< bounding offset radius r (world units)
};

/// Computes the offset radius r and the projection bounds for primitives whose unfattened
/// bounding rectangles (TriangleRectangle) lie in `rect_bounds_W`, for the three orthographic
/// views along X, Y and Z rendered in `raster`, and distance query D = `distance` (0: contact).
/// r = D/2 + sqrt(3) p / 2 with p = max(2 d_X, 2 d_Y, 2 d_Z) taken over the fattened bounds,
/// plus the float32 rounding error of the coordinates the GPU sees. The derivation (a closed
/// form of the fixed point "bounds depend on r, r depends on bounds") is in bounding_offset.cc.
/// @pre rect_bounds_W not empty, finite; distance >= 0; raster sizes >= 1.
Projection ComputeProjection(const Eigen::AlignedBox3d& rect_bounds_W, const RasterFormat& raster,
                             double distance);

/// An oriented box: center, orthonormal right-handed axes (columns) and half extents >= 0.
struct Obb {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};

/// Returns the tightest rectangle enclosing triangle (a, b, c) with its first axis along the
/// longest edge, the second in the triangle's plane, the third along the normal (half extent
/// 0). Degenerate triangles get a valid frame: collinear ones a segment-shaped rectangle,
/// coincident vertices a point. Never NaN for finite input.
Obb TriangleRectangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Returns `box` grown by r on every side (the UOBB of a rectangle: thickness 2r on the normal).
Obb GrowObb(const Obb& box, double r);

/// Returns the box moved by the rigid transform X_WM (box given in frame M).
Obb TransformObb(const Eigen::Isometry3d& X_WM, const Obb& box_M);

/// Returns the world AABB of the box.
Eigen::AlignedBox3d ObbAabb(const Obb& box);

/// Returns the 8 corners: corner k = center + sum_i s_i(k) half_extents[i] axes.col(i) with
/// s_i(k) = ((k >> i) & 1) ? +1 : -1.
std::array<Eigen::Vector3d, 8> ObbCorners(const Obb& box);

/// 12 triangles over ObbCorners' numbering, counter-clockwise seen from outside.
extern const std::array<uint8_t, 36> kBoxTriangleCorners;

/// The paper's "bounded exact offset" of a triangle: three edge boxes, each bounding the
/// cylinder of radius r around an edge and its end spheres, and the prism between the triangle
/// shifted by +r and -r along its normal. Their union contains the exact offset.
struct BoundedExactOffset {
  std::array<Obb, 3> edge_boxes;
  std::array<Eigen::Vector3d, 6> prism;  ///< a+rn, b+rn, c+rn, a-rn, b-rn, c-rn
};

/// Returns the bounded exact offset of triangle (a, b, c) for radius r. Degenerate triangles
/// get a finite, valid bound (the prism collapses onto the edge boxes).
BoundedExactOffset ComputeBoundedExactOffset(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                             const Eigen::Vector3d& c, double r);

/// 8 triangles over BoundedExactOffset::prism's numbering (two caps, three sides split in
/// two), counter-clockwise seen from outside; for a degenerate prism it is still closed.
extern const std::array<uint8_t, 24> kPrismTriangleCorners;

}  // namespace far
