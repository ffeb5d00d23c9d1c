#include "far/geometry/internal/predicates.h"

#include <gmpxx.h>

#include <cmath>
#include <random>
#include <vector>

#include "exact_reference.h"
#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace far::internal {
namespace {

using Eigen::Vector3d;
using reference::ExactOrient2d;
using reference::ExactOrient3d;

Vector3d RandomPoint(std::mt19937_64& rng, double scale, const Vector3d& offset) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return offset + scale * Vector3d(u(rng), u(rng), u(rng));
}

// A point on the plane of a, b, c, rounded to double: almost always a tiny nonzero determinant,
// sometimes exactly zero.
Vector3d NearlyCoplanar(std::mt19937_64& rng, const Vector3d& a, const Vector3d& b,
                        const Vector3d& c) {
  std::uniform_real_distribution<double> u(-1.0, 2.0);
  return a + u(rng) * (b - a) + u(rng) * (c - a);
}

TEST(PredicatesTest, Orient3dMatchesExactOnRandomPoints) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 20000; ++i) {
    const Vector3d a = RandomPoint(rng, 1.0, Vector3d::Zero());
    const Vector3d b = RandomPoint(rng, 1.0, Vector3d::Zero());
    const Vector3d c = RandomPoint(rng, 1.0, Vector3d::Zero());
    const Vector3d d = RandomPoint(rng, 1.0, Vector3d::Zero());
    ASSERT_EQ(Orient3d(a, b, c, d), ExactOrient3d(a, b, c, d)) << "case " << i;
  }
}

TEST(PredicatesTest, Orient3dMatchesExactOnNearlyCoplanarPoints) {
  std::mt19937_64 rng(12);
  int zeros = 0;
  int near_zero = 0;
  for (double scale : {1e-6, 1.0, 1e3}) {
    for (const Vector3d& offset :
         {Vector3d(0, 0, 0), Vector3d(1e5, -1e5, 1e5), Vector3d(1e6, 1e6, -1e6)}) {
      for (int i = 0; i < 4000; ++i) {
        const Vector3d a = RandomPoint(rng, scale, offset);
        const Vector3d b = RandomPoint(rng, scale, offset);
        const Vector3d c = RandomPoint(rng, scale, offset);
        // Every tenth case a repeated point: exactly zero, through the filter.
        const Vector3d d = i % 10 == 0 ? b : NearlyCoplanar(rng, a, b, c);
        const int exact = ExactOrient3d(a, b, c, d);
        zeros += exact == 0;
        ASSERT_EQ(Orient3d(a, b, c, d), exact) << "scale " << scale << " case " << i;
        ASSERT_EQ(Orient3dExact(a, b, c, d), exact);
        // Relabelings change the sign as the permutation's parity.
        ASSERT_EQ(Orient3d(b, a, c, d), -exact);
        ASSERT_EQ(Orient3d(d, a, b, c), -exact);
        ASSERT_EQ(PlaneSide(a, b, c).Side(d), exact);
        // The floating-point value is tiny: the case exercises the filter's boundary.
        const Vector3d n = (b - a).cross(c - a);
        near_zero += std::abs(n.dot(d - a)) < 1e-10 * scale * scale * scale;
      }
    }
  }
  EXPECT_GT(zeros, 3000) << "repeated points must give exact zeros";
  EXPECT_GT(near_zero, 10000);
}

// The exact determinant det[b - a, c - a, d - a] as a rational.
mpq_class ExactDet3(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  const auto q = [](double x) { return mpq_class(x); };
  const mpq_class ux = q(b.x()) - q(a.x()), uy = q(b.y()) - q(a.y()), uz = q(b.z()) - q(a.z());
  const mpq_class vx = q(c.x()) - q(a.x()), vy = q(c.y()) - q(a.y()), vz = q(c.z()) - q(a.z());
  const mpq_class wx = q(d.x()) - q(a.x()), wy = q(d.y()) - q(a.y()), wz = q(d.z()) - q(a.z());
  return ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx);
}

// |value - exact| / |exact| (0 when both are 0, infinite when only one is).
double RelativeError(double value, const mpq_class& exact) {
  if (sgn(exact) == 0) return value == 0.0 ? 0.0 : HUGE_VAL;
  const mpq_class error = (mpq_class(value) - exact) / exact;
  return std::abs(error.get_d());
}

TEST(PredicatesTest, DeterminantValuesAreWithinTheirRelativeBound) {
  // Orient3dValue and Orient2dValue promise 2^-51 relative (zero exactly when the points are
  // coplanar or collinear): checked on generic, nearly degenerate and far-off points, where
  // both the double-double path and the exact expansions answer.
  std::mt19937_64 rng(13);
  double worst3 = 0, worst2 = 0;
  for (double scale : {1e-6, 1.0, 1e3}) {
    for (const Vector3d& offset :
         {Vector3d(0, 0, 0), Vector3d(1e5, -1e5, 1e5), Vector3d(1e9, 1e9, -1e9)}) {
      for (int i = 0; i < 2000; ++i) {
        const Vector3d a = RandomPoint(rng, scale, offset);
        const Vector3d b = RandomPoint(rng, scale, offset);
        const Vector3d c = RandomPoint(rng, scale, offset);
        const Vector3d d = i % 3 == 0   ? RandomPoint(rng, scale, offset)
                           : i % 3 == 1 ? NearlyCoplanar(rng, a, b, c)
                                        : RandomPoint(rng, scale, Vector3d::Zero());
        const double e3 = RelativeError(Orient3dValue(a, b, c, d), ExactDet3(a, b, c, d));
        ASSERT_LE(e3, 0x1p-51) << "scale " << scale << " case " << i;
        worst3 = std::max(worst3, e3);
        const mpq_class det2 = (mpq_class(b.x()) - a.x()) * (mpq_class(c.y()) - a.y()) -
                               (mpq_class(b.y()) - a.y()) * (mpq_class(c.x()) - a.x());
        const double e2 =
            RelativeError(Orient2dValue(a.x(), a.y(), b.x(), b.y(), c.x(), c.y()), det2);
        ASSERT_LE(e2, 0x1p-51) << "scale " << scale << " case " << i;
        worst2 = std::max(worst2, e2);
      }
    }
  }
  std::printf("largest relative errors: Orient3dValue %.3g u, Orient2dValue %.3g u\n",
              worst3 / 0x1p-53, worst2 / 0x1p-53);
}

TEST(PredicatesTest, Orient3dIsZeroOnGridCoplanarPoints) {
  // Points on the plane z = x/2 + y/4 with dyadic coordinates: exactly coplanar.
  std::mt19937_64 rng(13);
  std::uniform_int_distribution<int> k(-64, 64);
  for (int i = 0; i < 2000; ++i) {
    std::vector<Vector3d> p;
    for (int j = 0; j < 4; ++j) {
      const double x = k(rng) / 8.0;
      const double y = k(rng) / 8.0;
      p.emplace_back(1e6 + x, -1e6 + y, 1e5 + x / 2 + y / 4);
    }
    ASSERT_EQ(Orient3d(p[0], p[1], p[2], p[3]), 0) << "case " << i;
    const Vector3d above(p[3].x(), p[3].y(), std::nextafter(p[3].z(), 2e5));
    ASSERT_EQ(Orient3d(p[0], p[1], p[2], above), ExactOrient3d(p[0], p[1], p[2], above));
  }
}

TEST(PredicatesTest, Orient3dSeesOneUlpAtLargeCoordinates) {
  const Vector3d a(1e6, 1e6, 1e6);
  const Vector3d b(1e6 + 1, 1e6, 1e6);
  const Vector3d c(1e6, 1e6 + 1, 1e6);
  const Vector3d on(1e6 + 0.25, 1e6 + 0.25, 1e6);
  const Vector3d above(1e6 + 0.25, 1e6 + 0.25, std::nextafter(1e6, 2e6));
  const Vector3d below(1e6 + 0.25, 1e6 + 0.25, std::nextafter(1e6, 0.0));
  EXPECT_EQ(Orient3d(a, b, c, on), 0);
  EXPECT_EQ(Orient3d(a, b, c, above), 1);
  EXPECT_EQ(Orient3d(a, b, c, below), -1);
}

TEST(PredicatesTest, Orient2dMatchesExact) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> t(-1.0, 2.0);
  std::uniform_int_distribution<int> k(-8, 8);
  int zeros = 0;
  for (double offset : {0.0, 1e5, 1e6}) {
    for (int i = 0; i < 10000; ++i) {
      double ax = offset + u(rng), ay = offset + u(rng);
      double bx = offset + u(rng), by = offset + u(rng);
      double cx, cy;
      if (i % 5 == 0) {  // exactly collinear: integer steps from an integer point
        ax = std::round(ax);
        ay = std::round(ay);
        const int dx = k(rng), dy = k(rng), m = k(rng);
        bx = ax + dx;
        by = ay + dy;
        cx = ax + m * dx;
        cy = ay + m * dy;
        if (i % 10 == 0) cy = std::nextafter(cy, 0.0);  // and one ulp off the line
      } else if (i % 2 == 0) {
        cx = offset + u(rng);
        cy = offset + u(rng);
      } else {  // nearly collinear
        const double s = t(rng);
        cx = ax + s * (bx - ax);
        cy = ay + s * (by - ay);
      }
      const int exact = ExactOrient2d(ax, ay, bx, by, cx, cy);
      zeros += exact == 0;
      ASSERT_EQ(Orient2d(ax, ay, bx, by, cx, cy), exact) << "case " << i;
      ASSERT_EQ(Orient2dExact(ax, ay, bx, by, cx, cy), exact);
      ASSERT_EQ(Orient2d(bx, by, ax, ay, cx, cy), -exact);
    }
  }
  EXPECT_GT(zeros, 1000);
}

TEST(PredicatesTest, Collinear3dMatchesExactCrossProduct) {
  std::mt19937_64 rng(15);
  std::uniform_int_distribution<int> k(-3, 3);
  for (int i = 0; i < 5000; ++i) {
    const Vector3d a(k(rng), k(rng), k(rng));
    const Vector3d b(k(rng), k(rng), k(rng));
    const Vector3d c(k(rng), k(rng), k(rng));
    const bool collinear = (b - a).cross(c - a).isZero(0.0);  // exact for small integers
    ASSERT_EQ(Collinear3d(a, b, c), collinear);
    const Vector3d shifted = c + Vector3d(0, 0, 1e-12);
    ASSERT_EQ(Collinear3d(a, b, shifted),
              ExactOrient2d(a.x(), a.y(), b.x(), b.y(), shifted.x(), shifted.y()) == 0 &&
                  ExactOrient2d(a.y(), a.z(), b.y(), b.z(), shifted.y(), shifted.z()) == 0 &&
                  ExactOrient2d(a.z(), a.x(), b.z(), b.x(), shifted.z(), shifted.x()) == 0);
  }
}

TEST(PredicatesTest, RoundedCrossIsWithinTwoUlpsOfExact) {
  std::mt19937_64 rng(16);
  const mpq_class tolerance = mpq_class(1, 1) / (mpq_class(1) << 52);  // 2^-52 relative
  for (int i = 0; i < 5000; ++i) {
    const Vector3d offset = i % 2 ? Vector3d(1e6, -1e5, 3e5) : Vector3d::Zero();
    const Vector3d a = RandomPoint(rng, 1.0, offset);
    const Vector3d b = RandomPoint(rng, 1.0, offset);
    // Nearly parallel second edge: c, d near the line through a, b.
    const Vector3d c = a + 0.3 * (b - a) + Vector3d(1e-9, -2e-9, 0);
    const Vector3d d = a + 0.9 * (b - a);
    const Vector3d n = RoundedCross(a, b, c, d);
    const reference::QVec qa = reference::ToQ(a), qb = reference::ToQ(b);
    const reference::QVec qc = reference::ToQ(c), qd = reference::ToQ(d);
    const mpq_class ux = qb.x - qa.x, uy = qb.y - qa.y, uz = qb.z - qa.z;
    const mpq_class vx = qd.x - qc.x, vy = qd.y - qc.y, vz = qd.z - qc.z;
    const mpq_class exact[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    for (int k = 0; k < 3; ++k) {
      const mpq_class error = abs(mpq_class(n[k]) - exact[k]);
      ASSERT_LE(error, tolerance * abs(exact[k])) << "case " << i << " component " << k;
    }
  }
}

// Coordinates on a grid, so that every difference is exact (the fused multiply-add path):
// parallel edges give exactly zero, and one grid step off parallel gives the exact minors.
TEST(PredicatesTest, RoundedCrossIsExactOnGridPoints) {
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<int> coordinate(-1000, 1000);
  const auto grid_point = [&](double step, const Vector3d& offset) {
    return Vector3d(Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)) * step + offset);
  };
  for (int i = 0; i < 5000; ++i) {
    const double step = i % 3 == 0 ? 1.0 : (i % 3 == 1 ? 0x1p-20 : 0x1p10);
    const Vector3d offset =
        i % 2 ? Vector3d(Vector3d(0x1p20, -0x1p18, 0x1p19) * step) : Vector3d::Zero();
    const Vector3d a = grid_point(step, offset);
    const Vector3d b = grid_point(step, offset);
    const Vector3d c = grid_point(step, offset);
    const int k = coordinate(rng) % 7 + 8;  // 2..14
    const Vector3d d = c + k * (b - a);
    const Vector3d parallel = RoundedCross(a, b, c, d);
    ASSERT_EQ(parallel, Vector3d::Zero()) << "case " << i;
    const Vector3d d_off = d + Vector3d(0, step, 0);
    const Vector3d n = RoundedCross(a, b, c, d_off);
    // (b - a) x (d_off - c) = (b - a) x (0, step, 0) exactly, for the parallel part vanishes.
    const Vector3d u = b - a;
    ASSERT_EQ(n, Vector3d(-u.z() * step, 0.0, u.x() * step)) << "case " << i;
  }
}

}  // namespace
}  // namespace far::internal
