#include "piece_footprint.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace far::internal {
namespace {

Eigen::Vector3d Point(const std::array<float, 3>& p) { return {p[0], p[1], p[2]}; }

// A box of half extents h (grown by R on each axis in the vertex shader): its projection's area
// is at most half its surface, 4 ((hu+R)(hv+R) + (hv+R)(hn+R) + (hn+R)(hu+R)).
PieceFootprint Box(const std::array<float, 3>& h) {
  const double u = std::abs(h[0]), v = std::abs(h[1]), n = std::abs(h[2]);
  return {4 * (u * v + v * n + n * u), 8 * (u + v + n), 12};
}

// A triangle (its projection's area is at most its own, its perimeter at most its own), or the
// prism of the triangle shifted by +-R along its normal: the projection of the shift adds at most
// a strip 2R wide along the triangle's diameter (at most half its perimeter).
PieceFootprint Triangle(const PieceInstance& piece) {
  const Eigen::Vector3d a = Point(piece.p[0]), b = Point(piece.p[1]), c = Point(piece.p[2]);
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
  return {area, perimeter, 0};
}

}  // namespace

PieceFootprint FootprintOf(PieceSet set, const PieceInstance& piece) {
  switch (set) {
    case PieceSet::kUobb:
    case PieceSet::kEdgeBoxes:
    case PieceSet::kProxyBoxes:
      return Box(piece.p[3]);
    case PieceSet::kPrisms:
    case PieceSet::kTriangles:
      return Triangle(piece);
  }
  return {};
}

double ViewScale::Pixels(const PieceFootprint& sum, uint64_t count) const {
  const double s = px_per_unit, r = radius, n = static_cast<double>(count);
  const double world = sum.area + r * sum.linear + r * r * sum.grown;
  // The fringe: a pixel whose center is outside the shape by less than a pixel may be drawn.
  const double fringe = s * (sum.linear + 2 * M_PI * r * n) + 4 * n;
  return std::min(s * s * world + fringe, n * view_pixels);
}

}  // namespace far::internal
