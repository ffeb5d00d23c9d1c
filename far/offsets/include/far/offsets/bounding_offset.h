#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "far/model/step_request.h"

namespace far {

/// Returns RES(Z) = 1 / (the largest step between adjacent depth values in [0, 1]):
/// 2^16 - 1 and 2^24 - 1 for the normalized formats, 2^24 for float32 (steps in [1/2, 1)).
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
  Eigen::Vector3d center_W;      ///< bounds_W's center: subtracted in double before float32
  double radius = 0;             ///< bounding offset radius r (world units), > 0
  /// What r covers, so that a reply can show it (far::LevelCertificate): with D the distance
  /// query, r >= D/2 + sqrt(3) max(pixel_size, depth_step) + rounding.
  double pixel_size = 0;  ///< the largest pixel side over the three views, world units
  double depth_step = 0;  ///< the largest step between depth values, world units
  double rounding = 0;    ///< bound on the float32 rounding of what the GPU draws, world units
};

/// Computes the offset radius r and the projection bounds for primitives whose unfattened
/// bounding rectangles (TriangleRectangle) lie in `rect_bounds_W`, for the three orthographic
/// views along X, Y and Z rendered in `raster`, and distance query D = `distance` (0: contact).
/// r = D/2 + sqrt(3) p / 2 with p = max(2 d_X, 2 d_Y, 2 d_Z) taken over the fattened bounds,
/// plus the float32 rounding error of the coordinates the GPU sees (relative to center_W).
/// bounds_W is rect_bounds_W grown by sqrt(3) r plus a margin, which contains every
/// GrowObb(rect, r) and every ComputeBoundedExactOffset(..., r) piece of those primitives.
/// The derivation (a closed form of the fixed point "bounds depend on r, r depends on bounds")
/// is in src/offsets/bounding_offset.cc and docs/bounding-offsets.md.
/// @pre rect_bounds_W not empty, finite, |coordinates| <= 2^100; 0 <= distance <= 2^100;
///      raster width and height >= 8 (below that no r exists: r grows the bounds faster than
///      it covers them).
/// @throws std::invalid_argument when a precondition is violated (callers' bug, not client
///      data). Thread-safe (pure function).
Projection ComputeProjection(const Eigen::AlignedBox3d& rect_bounds_W, const RasterFormat& raster,
                             double distance);

/// An oriented box: center, orthonormal right-handed axes (columns) and half extents >= 0.
struct Obb {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};

/// Returns the tightest rectangle enclosing triangle (a, b, c) with its first axis along the
/// longest edge, the second in the triangle's plane, the third along the normal n, oriented so
/// that a, b, c is counter-clockwise seen from +n (half extent 0 up to the normal's rounding).
/// Conservative by construction: every half extent carries 2^-48 (max |coordinate| + longest
/// edge), so the box contains the triangle despite rounding, in double, without tolerance.
/// Degenerate triangles get a valid frame: collinear ones a segment-shaped rectangle (n any
/// unit vector perpendicular to the segment, chosen deterministically), coincident vertices a
/// point (identity axes). Never NaN for finite input with finite coordinate differences.
Obb TriangleRectangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Returns `box` grown by r on every side (the UOBB of a rectangle: thickness 2r on the normal),
/// each half extent rounded up by a relative 2^-48 so that it contains the exact Minkowski sum
/// with the ball of radius r despite rounding. @pre r >= 0.
Obb GrowObb(const Obb& box, double r);

/// Returns the box moved by the rigid transform X_WM (box given in frame M).
Obb TransformObb(const Eigen::Isometry3d& X_WM, const Obb& box_M);

/// Returns the world AABB of the box, rounded outward (it contains ObbCorners' results).
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
  std::array<Eigen::Vector3d, 6> prism;  ///< a+tn, b+tn, c+tn, a-tn, b-tn, c-tn; t >= r
};

/// Returns the bounded exact offset of triangle (a, b, c) for radius r, conservative by
/// construction in double like TriangleRectangle. n is TriangleRectangle's normal. The edge
/// boxes contain the ball of radius rho around every point of their edge (axes e, n x e, n;
/// half extents |e|/2 + rho, rho, rho) and the prism's offset is t = rho, with
/// rho = r / cos(tilt) + 2^-48 (max |coordinate| + longest edge): tilt bounds the rounding
/// error of the normal's direction (<= 2^-12), so rho exceeds r by at most about 2^-25 r plus
/// that slack. A triangle too thin for a trustworthy normal (collinear, repeated vertices,
/// height below about 2^-35 of its longest edge) gets rho = r + height + 2 slack, and its
/// prism (t = r + slack) lies inside its longest edge's box: the edge boxes alone bound the
/// offset; everything stays finite.
/// Growing the r = 0 result by r afterwards misses at most r (1/cos(tilt) - 1) <= 2^-25 r.
/// @pre r >= 0, finite.
BoundedExactOffset ComputeBoundedExactOffset(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                             const Eigen::Vector3d& c, double r);

/// 8 triangles over BoundedExactOffset::prism's numbering (two caps, three sides split in
/// two), counter-clockwise seen from outside whatever the triangle's winding (n follows it);
/// for a degenerate prism it is still closed (every edge used twice, in opposite directions).
extern const std::array<uint8_t, 24> kPrismTriangleCorners;

}  // namespace far
