// Per-triangle bounding offsets: the rectangle that a UOBB grows, and the bounded exact offset.
//
// Both are conservative by construction in double precision: every half extent carries the
// frame's `slack` (32 units of roundoff of the coordinates' magnitude) and is rounded up, so a
// point of the triangle grown by a sphere of radius r, computed by a caller in double, tests
// inside without any tolerance. docs/bounding-offsets.md has the geometry.

#include <cmath>

#include "triangle_frame.h"

#include "far/offsets/bounding_offset.h"

namespace far {

using internal::ComputeTriangleFrame;
using internal::RoundUp;
using internal::TriangleFrame;

namespace {

// Tilt of the computed normal up to which the prism (thickened by 1/cos) is used; beyond it
// the triangle is so thin (height < 2^-35 L) that the edge boxes alone bound its offset.
constexpr double kMaxPrismTilt = 0x1p-12;

}  // namespace

Obb TriangleRectangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Vector3d& c) {
  const TriangleFrame frame = ComputeTriangleFrame(a, b, c);
  // Measure the vertices in the frame, relative to the longest edge's start (small numbers:
  // no cancellation against the absolute position). The origin itself measures 0.
  const Eigen::Vector3d& origin = frame.vertices[frame.longest];
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& vertex : frame.vertices) {
    const Eigen::Vector3d t = frame.axes.transpose() * (vertex - origin);
    lo = lo.cwiseMin(t);
    hi = hi.cwiseMax(t);
  }
  // The normal's extent is measured too: it is 0 up to the normal's rounding (larger for
  // slivers), and measuring it keeps the box a box of the actual vertices.
  Obb box;
  box.axes = frame.axes;
  box.center = origin + frame.axes * (0.5 * (lo + hi));
  box.half_extents = (0.5 * (hi - lo)).array() + frame.slack;
  return box;
}

BoundedExactOffset ComputeBoundedExactOffset(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                             const Eigen::Vector3d& c, double r) {
  const TriangleFrame frame = ComputeTriangleFrame(a, b, c);
  const Eigen::Vector3d n = frame.axes.col(2);

  // A point q + s of the offset (q in the triangle, |s| <= r) lies in the prism {q' + t n,
  // |t| <= r / cos(tilt)} when q' (q + s moved along n into the plane) stays in the triangle,
  // and otherwise within r / cos(tilt) of an edge. A triangle too thin for a trustworthy
  // normal is within `height` of its longest edge: the edge boxes alone bound its offset,
  // with the ball radius r + height, and the (then redundant) prism is kept inside them.
  // In that case the ball gets a second slack so that the prism's rounded vertices stay
  // strictly inside.
  const bool planar = frame.tilt_bound <= kMaxPrismTilt;
  const double rho =
      planar ? RoundUp(r / std::sqrt(1 - frame.tilt_bound * frame.tilt_bound)) + frame.slack
             : RoundUp(r + frame.height) + 2 * frame.slack;
  const double prism_offset = planar ? rho : RoundUp(r) + frame.slack;

  BoundedExactOffset offset;
  for (int i = 0; i < 3; ++i) {
    // Each edge box contains the ball of radius rho around every point of its edge, whatever
    // its rotation about the edge: axes e, n x e, n with n made perpendicular to e.
    const Eigen::Vector3d& start = frame.vertices[i];
    const Eigen::Vector3d e = frame.vertices[(i + 1) % 3] - start;
    const double length = internal::SafeNorm(e);
    Obb& box = offset.edge_boxes[i];
    box.center = start + 0.5 * e;
    if (length == 0) {
      box.axes = frame.axes;  // a repeated vertex: a cube around it
    } else {
      const Eigen::Vector3d dir = internal::SafeNormalized(e);
      Eigen::Vector3d normal = n - n.dot(dir) * dir;
      const double normal_length = normal.norm();
      if (normal_length > 0.5) {
        normal /= normal_length;
      } else {  // only for degenerate triangles, where any rotation about the edge will do
        normal = internal::AnyPerpendicular(dir);
        if (normal.dot(n) < 0) normal = -normal;
      }
      box.axes.col(0) = dir;
      box.axes.col(1) = normal.cross(dir);
      box.axes.col(2) = normal;
    }
    box.half_extents = Eigen::Vector3d(RoundUp(0.5 * length) + frame.slack + rho, rho, rho);
  }
  for (int i = 0; i < 3; ++i) {
    offset.prism[i] = frame.vertices[i] + prism_offset * n;
    offset.prism[i + 3] = frame.vertices[i] - prism_offset * n;
  }
  return offset;
}

// Caps 0-1-2 (+n: the triangle's own winding) and 3-5-4 (-n); the side on edge i -> j is the
// quad i, j, j+3, i+3, split as (i, i+3, j+3) and (i, j+3, j). Each triangle's normal
// (p1 - p0) x (p2 - p0) points out of the prism (for the side of edge a->b it is along
// (b - a) x n, outward for a counter-clockwise triangle seen from +n).
const std::array<uint8_t, 24> kPrismTriangleCorners = {
    0, 1, 2, 3, 5, 4,  // caps
    0, 3, 4, 0, 4, 1,  // side a-b
    1, 4, 5, 1, 5, 2,  // side b-c
    2, 5, 3, 2, 3, 0,  // side c-a
};

}  // namespace far
