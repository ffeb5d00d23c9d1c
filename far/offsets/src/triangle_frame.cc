#include "triangle_frame.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace far::internal {
namespace {

// Returns x scaled by a power of two (exactly) so that its largest |component| is in [1, 2).
// @pre x != 0, finite.
Eigen::Vector3d ScaledToUnitRange(const Eigen::Vector3d& x) {
  const int exponent = std::ilogb(x.cwiseAbs().maxCoeff());
  return Eigen::Vector3d(std::ldexp(x.x(), -exponent), std::ldexp(x.y(), -exponent),
                         std::ldexp(x.z(), -exponent));
}

}  // namespace

double SafeNorm(const Eigen::Vector3d& x) {
  const double largest = x.cwiseAbs().maxCoeff();
  if (largest == 0) return 0;
  const int exponent = std::ilogb(largest);
  return std::ldexp(ScaledToUnitRange(x).norm(), exponent);
}

Eigen::Vector3d SafeNormalized(const Eigen::Vector3d& x) {
  const Eigen::Vector3d scaled = ScaledToUnitRange(x);
  return scaled / scaled.norm();
}

Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& u) {
  int axis = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(u[i]) < std::abs(u[axis])) axis = i;
  }
  // |u[axis]| <= 1/sqrt(3), so |u x e_axis| >= sqrt(2/3): no cancellation.
  return SafeNormalized(u.cross(Eigen::Vector3d::Unit(axis)));
}

TriangleFrame ComputeTriangleFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c) {
  TriangleFrame frame;
  frame.vertices = {a, b, c};
  const auto& p = frame.vertices;

  // The longest edge (lowest index on ties) fixes u and the origin of all measurements.
  std::array<Eigen::Vector3d, 3> edges;
  std::array<double, 3> lengths{};
  for (int i = 0; i < 3; ++i) {
    edges[i] = p[(i + 1) % 3] - p[i];
    lengths[i] = SafeNorm(edges[i]);
    if (lengths[i] > lengths[frame.longest]) frame.longest = i;
  }
  const int k = frame.longest;
  frame.length = lengths[k];

  // Rounding slack relative to the coordinates' magnitude (a triangle far from the origin
  // carries the absolute error of its position), plus a few subnormals for the origin.
  double magnitude = 0;
  for (const auto& vertex : p) magnitude = std::max(magnitude, vertex.cwiseAbs().maxCoeff());
  frame.slack =
      kInflation * (magnitude + frame.length) + 64 * std::numeric_limits<double>::denorm_min();

  // Three coincident vertices: the identity frame, a point.
  if (frame.length == 0) {
    frame.tilt_bound = std::numeric_limits<double>::infinity();
    return frame;
  }
  const Eigen::Vector3d u = SafeNormalized(edges[k]);

  // The normal from the two shorter edges, which meet at the vertex opposite the longest
  // edge: their product |x||y| is the smallest, and so is the cross product's rounding error
  // relative to |x X y| (it is 1 / sin of the largest angle, at worst 1/sin 60 for a fat
  // triangle). The cyclic order (o, p[k], p[k+1]) keeps the sign of (b - a) x (c - a).
  const Eigen::Vector3d& o = p[(k + 2) % 3];
  const Eigen::Vector3d x = p[k] - o;
  const Eigen::Vector3d y = p[(k + 1) % 3] - o;
  Eigen::Vector3d n_raw = Eigen::Vector3d::Zero();
  double noise = 0;  // |x||y| in the scaled units of n_raw
  if (x != Eigen::Vector3d::Zero() && y != Eigen::Vector3d::Zero()) {
    // Power-of-two scaling is exact and keeps the product away from overflow and underflow.
    const Eigen::Vector3d xs = ScaledToUnitRange(x);
    const Eigen::Vector3d ys = ScaledToUnitRange(y);
    n_raw = xs.cross(ys);
    noise = xs.norm() * ys.norm();
  }

  // Make n exactly perpendicular to u (it is already, up to rounding, when it is meaningful).
  const Eigen::Vector3d n_perp = n_raw - n_raw.dot(u) * u;
  const double n_length = n_perp.norm();
  Eigen::Vector3d n;
  if (n_length > 128 * kDoubleUnit * noise && n_length > 0) {
    // The computed cross product is within ~16 kDoubleUnit |x||y| of the exact one; after
    // dividing by its length that is an angle, doubled here for the exact length's deficit,
    // plus a few units for u's own error and the normalizations.
    n = n_perp / n_length;
    frame.tilt_bound = 64 * kDoubleUnit * noise / n_length + 16 * kDoubleUnit;
  } else {
    // Collinear (or a repeated vertex): the cross product is rounding noise. Any
    // perpendicular works; keep the noise's sign so near-degenerate windings stay consistent.
    n = AnyPerpendicular(u);
    if (n.dot(n_raw) < 0) n = -n;
    frame.tilt_bound = std::numeric_limits<double>::infinity();
  }
  Eigen::Vector3d v = n.cross(u);
  v /= v.norm();
  frame.axes.col(0) = u;
  frame.axes.col(1) = v;
  frame.axes.col(2) = n;

  // The vertex opposite the longest edge projects inside that edge (both angles at its ends
  // are acute), so every triangle point lies within this distance of the edge segment.
  const Eigen::Vector3d w = o - p[k];
  frame.height = RoundUp(SafeNorm(w - w.dot(u) * u)) + kInflation * frame.length;
  return frame;
}

}  // namespace far::internal
