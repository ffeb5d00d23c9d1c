// Contact geometry of triangle pairs (TriangleContactGeometry, TriangleClosestPoints) against
// the exact rational reference: every point within the documented bound of an exact one, every
// exact extreme point of the intersection found, one point exactly when they touch at one point.

#include "far/geometry/triangle_contact.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "exact_reference.h"
#include "hard_cases.h"
#include "triangle_test_scenes.h"
#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace far {
namespace {

using Eigen::Vector3d;
using reference::QVec;

constexpr double kU = 0x1p-53;
// The documented bounds (docs/culling.md, "Contact geometry"): per coordinate, 16 u M for a
// contact point, M the largest coordinate magnitude of the pair.
constexpr double kContactBound = 16.0;

double LargestMagnitude(const TrianglePoints& s, const TrianglePoints& t) {
  double m = 0;
  for (const Vector3d* p : {&s.a, &s.b, &s.c, &t.a, &t.b, &t.c})
    m = std::max(m, p->cwiseAbs().maxCoeff());
  return m;
}

// The largest coordinate difference between a double point and an exact one.
double MaxError(const Vector3d& p, const QVec& q) {
  const mpq_class dx = mpq_class(p.x()) - q.x, dy = mpq_class(p.y()) - q.y,
                  dz = mpq_class(p.z()) - q.z;
  return std::max({std::abs(dx.get_d()), std::abs(dy.get_d()), std::abs(dz.get_d())});
}

struct Worst {
  double ratio = 0;  // largest error seen, in u M
  std::string where;
};

// Checks one intersecting pair; returns the largest error in units of u M.
void CheckContact(const TrianglePoints& s, const TrianglePoints& t, const std::string& name,
                  Worst& worst) {
  const ContactGeometry g = TriangleContactGeometry(s, t);
  const std::vector<QVec> exact = reference::ExactIntersectionExtremes(s, t);
  ASSERT_FALSE(exact.empty()) << name;
  const double unit = kU * std::max(LargestMagnitude(s, t), 1e-300);
  const double bound = kContactBound * unit;
  ASSERT_GE(g.num_points, 1) << name;
  ASSERT_LE(g.num_points, ContactGeometry::kMaxPoints) << name;
  // Every reported point is near an exact extreme point...
  for (int k = 0; k < g.num_points; ++k) {
    double best = HUGE_VAL;
    for (const QVec& q : exact) best = std::min(best, MaxError(g.points[k], q));
    EXPECT_LE(best, bound) << name << ": point " << k;
    if (best / unit > worst.ratio) worst = {best / unit, name};
  }
  // ...and every exact extreme point near a reported one, unless it is within twice the bound
  // of another extreme point (then rounding may merge them in a coplanar polygon's hull).
  for (size_t e = 0; e < exact.size(); ++e) {
    double best = HUGE_VAL;
    for (int k = 0; k < g.num_points; ++k) best = std::min(best, MaxError(g.points[k], exact[e]));
    bool crowded = false;
    for (size_t f = 0; f < exact.size(); ++f) {
      if (f == e) continue;
      const Vector3d other(exact[f].x.get_d(), exact[f].y.get_d(), exact[f].z.get_d());
      crowded = crowded || MaxError(other, exact[e]) <= 2 * bound + unit;
    }
    if (!crowded) {
      EXPECT_LE(best, bound) << name << ": exact extreme point " << e << " missed";
    }
  }
  // One point exactly when they touch at one point; two for a segment.
  if (exact.size() <= 2 || !g.coplanar) {
    EXPECT_EQ(g.num_points, static_cast<int>(exact.size())) << name;
  }
}

TEST(TriangleContactTest, CrossingTrianglesGiveTheirSegment) {
  const TrianglePoints s{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
  const TrianglePoints t{{1, 1, -1}, {1, 1, 1}, {3, 1, 0}};  // in y = 1, its corner (3, 1, 0) on s
  const ContactGeometry g = TriangleContactGeometry(s, t);
  ASSERT_EQ(g.num_points, 2);
  EXPECT_FALSE(g.coplanar);
  // t meets z = 0 on x in [1, 3] at y = 1, all inside s.
  const Vector3d lo = g.points[0].x() < g.points[1].x() ? g.points[0] : g.points[1];
  const Vector3d hi = g.points[0].x() < g.points[1].x() ? g.points[1] : g.points[0];
  EXPECT_EQ(lo, Vector3d(1, 1, 0));
  EXPECT_EQ(hi, Vector3d(3, 1, 0));
  EXPECT_EQ(g.normal_a, Vector3d(0, 0, 1));
  EXPECT_NEAR(g.normal_b.norm(), 1.0, 1e-14);
  EXPECT_NEAR(g.normal_b.y(), 1.0, 1e-14);  // (0, 0, 2) x (2, 0, 1) = (0, 4, 0)
}

TEST(TriangleContactTest, VertexOnFaceIsOnePoint) {
  const TrianglePoints s{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
  const TrianglePoints t{{1, 1, 0}, {1, 2, 3}, {2, 1, 3}};
  const ContactGeometry g = TriangleContactGeometry(s, t);
  ASSERT_EQ(g.num_points, 1);
  EXPECT_EQ(g.points[0], Vector3d(1, 1, 0));
}

TEST(TriangleContactTest, CoplanarStarGivesAHexagonCounterclockwise) {
  // Two triangles forming a six-pointed star: their overlap is a hexagon.
  const TrianglePoints s{{0, 2, 0}, {-std::sqrt(3.0), -1, 0}, {std::sqrt(3.0), -1, 0}};
  const TrianglePoints t{{0, -2, 0}, {std::sqrt(3.0), 1, 0}, {-std::sqrt(3.0), 1, 0}};
  const ContactGeometry g = TriangleContactGeometry(s, t);
  EXPECT_TRUE(g.coplanar);
  ASSERT_EQ(g.num_points, 6);
  // Counterclockwise about normal_a: consecutive cross products point along it.
  for (int k = 0; k < 6; ++k) {
    const Vector3d e1 = g.points[(k + 1) % 6] - g.points[k];
    const Vector3d e2 = g.points[(k + 2) % 6] - g.points[(k + 1) % 6];
    EXPECT_GT(e1.cross(e2).dot(g.normal_a), 0) << k;
  }
  Worst worst;
  CheckContact(s, t, "star", worst);
}

TEST(TriangleContactTest, CoplanarTrianglesSharingAnEdgeGiveTheEdge) {
  const TrianglePoints s{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  const TrianglePoints t{{0, 0, 0}, {2, 0, 0}, {1, -1, 0}};
  const ContactGeometry g = TriangleContactGeometry(s, t);
  ASSERT_EQ(g.num_points, 2);
  EXPECT_TRUE(g.coplanar);
}

TEST(TriangleContactTest, DegenerateTrianglesAreTheSegmentOrPointTheyAre) {
  const TrianglePoints face{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
  const TrianglePoints needle{{1, 1, -1}, {1, 1, 1}, {1, 1, 0.5}};  // collinear, crosses at (1,1,0)
  ContactGeometry g = TriangleContactGeometry(needle, face);
  ASSERT_EQ(g.num_points, 1);
  EXPECT_EQ(g.points[0], Vector3d(1, 1, 0));
  EXPECT_EQ(g.normal_a, Vector3d::Zero());
  const TrianglePoints lying{{-1, 1, 0}, {1, 1, 0}, {9, 1, 0}};  // collinear, in the face's plane
  g = TriangleContactGeometry(lying, face);
  ASSERT_EQ(g.num_points, 2);
  Worst worst;
  CheckContact(lying, face, "lying", worst);
  const TrianglePoints point{{1, 1, 0}, {1, 1, 0}, {1, 1, 0}};
  g = TriangleContactGeometry(face, point);
  ASSERT_EQ(g.num_points, 1);
  EXPECT_EQ(g.points[0], Vector3d(1, 1, 0));
}

TEST(TriangleContactTest, MatchesExactReferenceOnHardCases) {
  Worst worst;
  int checked = 0;
  for (const reference::HardCase& c : reference::MakeHardCases()) {
    if (!c.intersect) continue;
    const auto relabelings = reference::Relabelings(c.s, c.t);
    for (size_t r = 0; r < relabelings.size(); r += 7) {  // every 7th of the 72 relabelings
      CheckContact(relabelings[r].first, relabelings[r].second, c.name + "#" + std::to_string(r),
                   worst);
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  std::printf("hard cases: %d pairs checked, largest error %.3g u M (%s)\n", checked, worst.ratio,
              worst.where.c_str());
}

TEST(TriangleContactTest, MatchesExactReferenceOnRandomizedScenes) {
  for (const reference::PairScene& scene : reference::MakePairScenes()) {
    std::mt19937_64 rng(43);
    Worst worst;
    int checked = 0;
    for (int i = 0; i < scene.count && checked < 1500; ++i) {
      const auto [s, t] = scene.make(rng);
      if (!TrianglesIntersect(s, t)) continue;
      CheckContact(s, t, scene.name + "#" + std::to_string(i), worst);
      ++checked;
    }
    std::printf("%s: %d intersecting pairs, largest error %.3g u M (%s)\n", scene.name.c_str(),
                checked, worst.ratio, worst.where.c_str());
  }
}

TEST(TriangleContactTest, CrossingPairsFarFromTheOriginStayWithinTheBound) {
  std::mt19937_64 rng(1043);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double offset : {0.0, 1e6, 1e9}) {
    Worst worst;
    int checked = 0;
    while (checked < 500) {
      const Vector3d o(offset, -offset, 0.5 * offset);
      const auto p = [&] { return Vector3d(o + Vector3d(u(rng), u(rng), u(rng))); };
      const TrianglePoints s{p(), p(), p()}, t{p(), p(), p()};
      if (!TrianglesIntersect(s, t)) continue;
      CheckContact(s, t, "offset " + std::to_string(offset), worst);
      ++checked;
    }
    std::printf("offset %g: largest error %.3g u M\n", offset, worst.ratio);
  }
}

// --- Closest points -------------------------------------------------------------------------

// The distance bound of triangle_distance.cc (128 eps L) plus the rounding of the points.
void CheckClosestPoints(const TrianglePoints& s, const TrianglePoints& t, const std::string& name,
                        double& worst_on, double& worst_length) {
  const ClosestPoints c = TriangleClosestPoints(s, t);
  const double m = LargestMagnitude(s, t);
  Eigen::AlignedBox3d box;
  for (const Vector3d* p : {&s.a, &s.b, &s.c, &t.a, &t.b, &t.c}) box.extend(*p);
  const double l = box.diagonal().norm();
  const double unit = kU * std::max(l, m);
  // Each point lies on its triangle, within a few units.
  const double on_s =
      std::sqrt(reference::ExactSquaredDistance({c.point_a, c.point_a, c.point_a}, s).get_d());
  const double on_t =
      std::sqrt(reference::ExactSquaredDistance({c.point_b, c.point_b, c.point_b}, t).get_d());
  EXPECT_LE(on_s, 64 * unit) << name;
  EXPECT_LE(on_t, 64 * unit) << name;
  worst_on = std::max(worst_on, std::max(on_s, on_t) / unit);
  // Their distance is the pairs' distance.
  const double exact = std::sqrt(reference::ExactSquaredDistance(s, t).get_d());
  const double length = (c.point_b - c.point_a).norm();
  EXPECT_NEAR(length, exact, 160 * unit) << name;
  worst_length = std::max(worst_length, std::abs(length - exact) / unit);
}

TEST(TriangleContactTest, ClosestPointsMatchExactDistance) {
  for (const reference::PairScene& scene : reference::MakePairScenes()) {
    std::mt19937_64 rng(4343);
    double worst_on = 0, worst_length = 0;
    for (int i = 0; i < std::min(scene.count, 600); ++i) {
      const auto [s, t] = scene.make(rng);
      CheckClosestPoints(s, t, scene.name + "#" + std::to_string(i), worst_on, worst_length);
    }
    std::printf("%s: points off their triangles by at most %.3g u max(L, M), length off by %.3g\n",
                scene.name.c_str(), worst_on, worst_length);
  }
  double worst_on = 0, worst_length = 0;
  for (const reference::HardCase& c : reference::MakeHardCases()) {
    CheckClosestPoints(c.s, c.t, c.name, worst_on, worst_length);
    CheckClosestPoints(c.t, c.s, c.name + " swapped", worst_on, worst_length);
  }
  std::printf("hard cases: points off by %.3g, length off by %.3g (u max(L, M))\n", worst_on,
              worst_length);
}

TEST(TriangleContactTest, ClosestPointsOfSwappedPairsAreSwapped) {
  const TrianglePoints s{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const TrianglePoints t{{0.2, 0.2, 1}, {2, 0.2, 1}, {0.2, 2, 3}};
  const ClosestPoints a = TriangleClosestPoints(s, t);
  const ClosestPoints b = TriangleClosestPoints(t, s);
  EXPECT_EQ(a.point_a, b.point_b);
  EXPECT_EQ(a.point_b, b.point_a);
  EXPECT_EQ(a.point_a, Vector3d(0.2, 0.2, 0));
  EXPECT_EQ(a.point_b, Vector3d(0.2, 0.2, 1));
}

}  // namespace
}  // namespace far
