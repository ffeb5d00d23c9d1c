// The draw pacer's bound on a piece's screen area (far/gpu/src/piece_footprint.h, private to
// far::gpu: a pure function, tested here through its header): for random boxes and prisms in
// random orientations, grown by random radii, the exact area of the grown shape's projection
// along each axis never exceeds the bound, and a run's bound is the sum of its pieces'.
#include "piece_footprint.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace far::internal {
namespace {

std::array<float, 3> F(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}
Eigen::Vector3d D(const std::array<float, 3>& v) { return {v[0], v[1], v[2]}; }

// The area of the convex hull of 2D points (Andrew's monotone chain).
double HullArea(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  double area = 0;
  for (size_t i = 0; i + 1 < k; ++i)
    area += hull[i].x() * hull[i + 1].y() - hull[i + 1].x() * hull[i].y();
  return 0.5 * std::abs(area);
}

// The corners of the shape the vertex shader draws for `piece` grown by `r` (culling_shaders.cc).
std::vector<Eigen::Vector3d> DrawnCorners(PieceSet set, const PieceInstance& piece, double r) {
  std::vector<Eigen::Vector3d> corners;
  if (set == PieceSet::kPrisms) {
    for (int i = 0; i < 3; ++i) {
      for (double side : {1.0, -1.0}) corners.push_back(D(piece.p[i]) + side * r * D(piece.p[3]));
    }
    return corners;
  }
  const Eigen::Vector3d u = D(piece.p[1]), v = D(piece.p[2]), n = u.cross(v);
  const Eigen::Vector3d h = D(piece.p[3]) + Eigen::Vector3d::Constant(r);
  for (int k = 0; k < 8; ++k) {
    corners.push_back(D(piece.p[0]) + ((k & 1) ? 1 : -1) * h.x() * u +
                      ((k & 2) ? 1 : -1) * h.y() * v + ((k & 4) ? 1 : -1) * h.z() * n);
  }
  return corners;
}

TEST(PieceFootprintTest, BoundsTheProjectedAreaOfEveryGrownPieceAlongEveryAxis) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> unit(-1, 1), size(0, 2), radius(0, 0.5);
  double tightest = INFINITY;  // the smallest bound / area seen: how loose the bound is
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized())
            .toRotationMatrix();
    PieceInstance piece;
    PieceSet set;
    if (trial % 2 == 0) {
      set = PieceSet::kUobb;
      // Flat boxes (a triangle's rectangle), solid ones, and tiny ones (all radius).
      const double scale = trial % 6 == 0 ? 0.01 : 1.0;
      const Eigen::Vector3d h =
          scale * Eigen::Vector3d(size(rng), size(rng), trial % 4 == 0 ? 0.0 : size(rng));
      piece.p = {F(Eigen::Vector3d(unit(rng), unit(rng), unit(rng))), F(R.col(0)), F(R.col(1)),
                 F(h)};
    } else {
      set = PieceSet::kPrisms;
      const Eigen::Vector3d a(unit(rng), unit(rng), unit(rng)), b(unit(rng), unit(rng), unit(rng)),
          c(unit(rng), unit(rng), unit(rng));
      piece.p = {F(a), F(b), F(c), F((b - a).cross(c - a).normalized())};
    }
    const double r = radius(rng);
    const PieceFootprint f = FootprintOf(set, piece);
    const double bound = f.area + r * f.linear + r * r * f.grown;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<Eigen::Vector2d> projected;
      for (const Eigen::Vector3d& p : DrawnCorners(set, piece, r))
        projected.emplace_back(p[(axis + 1) % 3], p[(axis + 2) % 3]);
      const double area = HullArea(projected);
      // (float corners: a relative hair of rounding)
      EXPECT_LE(area, bound * (1 + 1e-5) + 1e-9) << "trial " << trial << " axis " << axis;
      if (area > 1e-3) tightest = std::min(tightest, bound / area);
    }
  }
  // Not so loose that it never comes near: some piece fills at least half its bound.
  EXPECT_LT(tightest, 2.0);
}

TEST(PieceFootprintTest, ViewPixelsGrowWithTheRunAndNeverExceedItsPiecesViewports) {
  PieceInstance piece;
  piece.p = {F({0, 0, 0}), F({1, 0, 0}), F({0, 1, 0}), F({0.5, 0.5, 0.01})};
  const PieceFootprint one = FootprintOf(PieceSet::kUobb, piece);
  PieceFootprint two = one;
  two += one;
  ViewScale scale{100, 0.02, 512 * 512};
  const double a = scale.Pixels(one, 1), b = scale.Pixels(two, 2);
  EXPECT_GT(a, 100 * 100 * 1.0);  // a 1 x 1 face seen face-on: 10,000 pixels at least
  EXPECT_DOUBLE_EQ(b, 2 * a);
  scale.px_per_unit = 1e4;  // a piece far larger than the viewport: one viewport
  EXPECT_DOUBLE_EQ(scale.Pixels(two, 2), 2.0 * 512 * 512);
}

}  // namespace
}  // namespace far::internal
