#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "exact_reference.h"
#include "hard_cases.h"
#include "triangle_test_scenes.h"
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "far/geometry/triangle_tests.h"

namespace far {
namespace {

using Eigen::Vector3d;
using reference::Describe;
using reference::ExactSquaredDistance;
using reference::Tri;

constexpr double kEps = 0x1p-53;
// The documented bound (triangle_distance.cc): d - 32 eps L <= d~ <= d + 128 eps L, and the
// predicate never misses d <= D and rejects d > D + 288 eps L.
constexpr double kUnder = 32.0;
constexpr double kOver = 128.0;
constexpr double kIncludeWindow = 288.0;

double PairScale(const TrianglePoints& s, const TrianglePoints& t) {
  Eigen::Array3d lo = s.a.array(), hi = s.a.array();
  for (const Vector3d* p : {&s.b, &s.c, &t.a, &t.b, &t.c}) {
    lo = lo.min(p->array());
    hi = hi.max(p->array());
  }
  return (hi - lo).matrix().norm();
}

// The smallest double D with D * D >= d2 (exactly): the tightest D for which distance <= D.
double SmallestDoubleAtLeast(const mpq_class& d2) {
  double d = std::sqrt(d2.get_d());
  while (mpq_class(d) * mpq_class(d) < d2) d = std::nextafter(d, HUGE_VAL);
  while (d > 0) {
    const double lower = std::nextafter(d, 0.0);
    if (mpq_class(lower) * mpq_class(lower) < d2) break;
    d = lower;
  }
  return d;
}

// Checks TriangleDistance and TrianglesWithinDistance on one pair against the exact squared
// distance. Returns an empty string on success, else what failed.
std::string CheckPair(const TrianglePoints& s, const TrianglePoints& t) {
  const mpq_class exact2 = ExactSquaredDistance(s, t);
  const double computed = TriangleDistance(s, t);
  const double scale = PairScale(s, t);
  const mpq_class q(computed);
  const mpq_class under = mpq_class(kUnder * kEps * scale);
  const mpq_class over = mpq_class(kOver * kEps * scale);
  if (!(computed >= 0)) return "negative or NaN distance";
  if (sgn(exact2) == 0 && computed != 0) return "intersecting pair with nonzero distance";
  // d <= d~ + 32 eps L, i.e. d~ is not too small.
  if (exact2 > (q + under) * (q + under)) return "distance underestimated beyond the bound";
  // d >= d~ - 128 eps L, i.e. d~ is not too large.
  if (q > over && exact2 < (q - over) * (q - over))
    return "distance overestimated beyond the bound";
  // The predicate never misses: at D = d (rounded up) it must answer true.
  const double tight = SmallestDoubleAtLeast(exact2);
  if (!TrianglesWithinDistance(s, t, tight)) return "predicate missed a pair at D = d";
  // The combined call accepts it too, with TriangleDistance's value.
  const std::optional<double> within = TriangleDistanceIfWithin(s, t, tight);
  if (!within) return "TriangleDistanceIfWithin missed a pair at D = d";
  if (*within != computed) return "TriangleDistanceIfWithin gave another distance";
  // And it rejects pairs farther than D + 288 eps L.
  const double far_below = tight - 2 * kIncludeWindow * kEps * scale;
  if (far_below > 0 && TrianglesWithinDistance(s, t, far_below)) {
    return "predicate included a pair beyond its documented window";
  }
  if (far_below > 0 && TriangleDistanceIfWithin(s, t, far_below)) {
    return "TriangleDistanceIfWithin included a pair beyond the predicate's window";
  }
  return {};
}

TEST(TriangleDistanceTest, GivesHandComputedDistances) {
  const TrianglePoints base = Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0));
  // Parallel planes: 2.
  EXPECT_DOUBLE_EQ(
      TriangleDistance(base, Tri(Vector3d(0, 0, 2), Vector3d(1, 0, 2), Vector3d(0, 1, 2))), 2.0);
  // Vertex above the face: 0.5.
  const Vector3d p(0.25, 0.25, 0.5);
  EXPECT_DOUBLE_EQ(TriangleDistance(base, Tri(p, p, p)), 0.5);
  // Skew edges: 3.
  EXPECT_DOUBLE_EQ(
      TriangleDistance(Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 0, -1)),
                       Tri(Vector3d(0.5, -1, 3), Vector3d(0.5, 1, 3), Vector3d(0.5, 0, 4))),
      3.0);
  // Intersecting: exactly 0.
  EXPECT_EQ(TriangleDistance(
                base, Tri(Vector3d(0.2, 0.2, -1), Vector3d(0.2, 0.2, 1), Vector3d(0.3, 0.2, 0))),
            0.0);
  // Collinear triangles on parallel lines 1 apart, and two points.
  EXPECT_DOUBLE_EQ(TriangleDistance(Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(2, 0, 0)),
                                    Tri(Vector3d(0, 1, 0), Vector3d(1, 1, 0), Vector3d(3, 1, 0))),
                   1.0);
  const Vector3d q(3, 4, 0);
  EXPECT_DOUBLE_EQ(
      TriangleDistance(Tri(Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()), Tri(q, q, q)),
      5.0);
}

TEST(TriangleDistanceTest, WithinDistanceIsExactForIntersectingAndFarPairs) {
  const TrianglePoints base = Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0));
  const TrianglePoints touching = Tri(Vector3d(1, 0, 0), Vector3d(2, 0, 1), Vector3d(2, 1, 1));
  EXPECT_TRUE(TrianglesWithinDistance(base, touching, 0.0));
  const TrianglePoints lifted = Tri(Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1, 1));
  EXPECT_TRUE(TrianglesWithinDistance(base, lifted, 1.0));
  EXPECT_FALSE(TrianglesWithinDistance(base, lifted, 0.999));
  EXPECT_FALSE(TrianglesWithinDistance(base, lifted, 0.0));
}

// A pair h apart, `offset` from the origin: TriangleDistance gives h (up to the rounding of the
// coordinates), TriangleDistanceIfWithin accepts it just above that distance with the same value,
// and rejects it just below where h is well above the coordinates' rounding.
void ExpectSplitAtSeparation(const TrianglePoints& s, const TrianglePoints& t, double h,
                             double offset) {
  SCOPED_TRACE(::testing::Message() << "offset " << offset << " h " << h);
  const double d = TriangleDistance(s, t);
  ASSERT_NEAR(d, h, 1e-9 * (1 + offset));
  const std::optional<double> above = TriangleDistanceIfWithin(s, t, d * (1 + 1e-6));
  ASSERT_TRUE(above.has_value());
  EXPECT_EQ(*above, d);
  if (h > 1e-6 * (1 + offset)) {
    EXPECT_FALSE(TriangleDistanceIfWithin(s, t, d * (1 - 1e-3)).has_value());
  }
}

// Slanted parallel triangles whose boxes overlap, so that only the normal axis (or the full
// distance) separates them: far from the origin too, at separations from 1e-9 to 1, each
// accepted at D just above the separation and rejected just below, with the same distance
// TriangleDistance gives.
TEST(TriangleDistanceTest, SlantedParallelPairsAreSplitAtTheirSeparation) {
  const Vector3d normal = Vector3d(1, 2, 3).normalized();
  for (const double offset : {0.0, 1e3, 1e6}) {
    const Vector3d o = Vector3d::Constant(offset);
    const TrianglePoints s =
        Tri(o + Vector3d(0, 0, 0), o + Vector3d(3, 0, -1), o + Vector3d(0, 3, -2));
    for (const double h : {1e-9, 1e-6, 1e-3, 0.1, 1.0}) {
      const Vector3d shift = h * normal + Vector3d(0.1, 0.2, 0).cross(normal);
      const TrianglePoints t = Tri(s.a + shift, s.b + shift, s.c + shift);
      ExpectSplitAtSeparation(s, t, h, offset);
    }
  }
}

// Two triangles whose closest features are crossing edges (one along x, the other along y, h
// above it, each triangle hanging away from the other), turned and moved far from the origin:
// the cross product of the two edges is the only axis that shows their gap, so the separating
// axes in front of the exact distance are tight here. Each pair is accepted at D just above its
// distance and rejected just below, with the distance TriangleDistance gives.
TEST(TriangleDistanceTest, CrossingEdgesAreSplitAtTheirSeparation) {
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  for (const double offset : {0.0, 1e3, 1e6}) {
    const Vector3d o = Vector3d(offset, -offset, 0.5 * offset);
    for (const double h : {1e-9, 1e-6, 1e-3, 0.1, 1.0}) {
      const TrianglePoints s = Tri(o + turn * Vector3d(-1, 0, 0), o + turn * Vector3d(1, 0, 0),
                                   o + turn * Vector3d(0.3, 0, -1));
      const TrianglePoints t = Tri(o + turn * Vector3d(0, -1, h), o + turn * Vector3d(0, 1, h),
                                   o + turn * Vector3d(0, -0.2, h + 1));
      ExpectSplitAtSeparation(s, t, h, offset);
    }
  }
}

TEST(TriangleDistanceTest, MatchesExactDistanceOnRandomizedScenes) {
  for (const reference::PairScene& scene : reference::MakePairScenes()) {
    std::mt19937_64 rng(777);
    int failures = 0;
    const int count = std::min(scene.count, 3000);
    for (int i = 0; i < count && failures < 5; ++i) {
      const auto [s, t] = scene.make(rng);
      const std::string problem = CheckPair(s, t);
      if (!problem.empty()) {
        ++failures;
        ADD_FAILURE() << scene.name << " case " << i << ": " << problem << " for "
                      << Describe(s, t);
      }
    }
  }
}

// The stages meet a pair in the order of its objects' slots, which follow a scene's history:
// the answer, rounding included, must not depend on which triangle comes first.
TEST(TriangleDistanceTest, IsSymmetricBitForBit) {
  int checked = 0;
  for (const reference::PairScene& scene : reference::MakePairScenes()) {
    std::mt19937_64 rng(991);
    for (int i = 0; i < std::min(scene.count, 500); ++i) {
      const auto [s, t] = scene.make(rng);
      const double d = TriangleDistance(s, t);
      ASSERT_EQ(d, TriangleDistance(t, s)) << scene.name << " case " << i << " " << Describe(s, t);
      for (const double limit : {0.0, 0.5 * d, d, std::nextafter(d, 0.0), 2 * d + 1}) {
        ASSERT_EQ(TriangleDistanceIfWithin(s, t, limit), TriangleDistanceIfWithin(t, s, limit))
            << scene.name << " case " << i << " limit " << limit << " " << Describe(s, t);
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(TriangleDistanceTest, MatchesExactDistanceOnHardCases) {
  int failures = 0;
  for (const reference::HardCase& c : reference::MakeHardCases()) {
    const auto relabelings = reference::Relabelings(c.s, c.t);
    for (size_t k = 0; k < relabelings.size() && failures < 10; k += 7) {
      const auto& [s, t] = relabelings[k];
      const std::string problem = CheckPair(s, t);
      if (!problem.empty()) {
        ++failures;
        ADD_FAILURE() << c.name << ": " << problem << " for " << Describe(s, t);
      }
    }
  }
}

TEST(TriangleDistanceTest, IsStableForNearlyParallelEdgesAndFaces) {
  // Edges at angles from 1e-1 down to 1e-16, at the origin and at 1e5, with separations from
  // 1e-9 to 1; also the faces of two nearly parallel triangles.
  int failures = 0;
  for (double offset : {0.0, 1e5}) {
    for (int k = 1; k <= 16; ++k) {
      for (double gap : {1e-9, 1e-4, 1.0}) {
        const double angle = std::pow(10.0, -k);
        const Vector3d o(offset, offset, offset);
        const TrianglePoints s =
            Tri(o + Vector3d(0, 0, 0), o + Vector3d(1, 0, 0), o + Vector3d(0.5, -1, -1));
        // t's first edge is nearly parallel to s's edge along x, overlapping it half-way.
        const TrianglePoints t = Tri(o + Vector3d(0.5, gap, 0), o + Vector3d(1.5, gap + angle, 0),
                                     o + Vector3d(1, 1, 1));
        // Nearly parallel faces: t2 is s tilted by `angle` and lifted by `gap`.
        const TrianglePoints s2 =
            Tri(o + Vector3d(0, 0, 0), o + Vector3d(1, 0, 0), o + Vector3d(0, 1, 0));
        const TrianglePoints t2 =
            Tri(o + Vector3d(0.25, 0.25, gap), o + Vector3d(1.25, 0.25, gap + angle),
                o + Vector3d(0.25, 1.25, gap));
        for (const auto& [a, b] : {std::make_pair(s, t), std::make_pair(s2, t2)}) {
          for (const auto& [a2, b2] : reference::Relabelings(a, b)) {
            const std::string problem = CheckPair(a2, b2);
            if (!problem.empty() && ++failures <= 5) {
              ADD_FAILURE() << "angle 1e-" << k << " gap " << gap << ": " << problem << " for "
                            << Describe(a2, b2);
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(TriangleDistanceTest, IsStableForSliversAndDegenerateTriangles) {
  const double h = std::ldexp(1.0, -27);  // aspect ratio 1.3e8
  const TrianglePoints cap = Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, h, 0));
  const TrianglePoints needle = Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(1, h, 0));
  const TrianglePoints segment = Tri(Vector3d(0, 0, 0), Vector3d(1, 1, 1), Vector3d(0.5, 0.5, 0.5));
  const Vector3d p(0.3, 0.2, 0.1);
  const TrianglePoints point = Tri(p, p, p);
  std::vector<TrianglePoints> others;
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Vector3d c(u(rng), u(rng) * 1e-6, u(rng) * 1e-6);
    others.push_back(Tri(c, c + Vector3d(u(rng), u(rng), u(rng)) * 1e-3,
                         c + Vector3d(u(rng), u(rng), u(rng)) * 1e-3));
    others.push_back(Tri(c, c, c + Vector3d(u(rng), u(rng), u(rng))));
    others.push_back(Tri(c, c, c));
  }
  int failures = 0;
  for (const TrianglePoints& shape : {cap, needle, segment, point}) {
    for (const TrianglePoints& other : others) {
      const std::string problem = CheckPair(shape, other);
      if (!problem.empty() && ++failures <= 5) {
        ADD_FAILURE() << problem << " for " << Describe(shape, other);
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(TriangleDistanceTest, NeverExceedsSampledUpperBound) {
  // Brute force: the distance of any two sampled points of the triangles bounds the distance
  // from above, and a fine sampling comes close to it.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 24;
  for (int i = 0; i < 100; ++i) {
    const auto p = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
    const TrianglePoints s{p(), p(), p()};
    const TrianglePoints t{p() + Vector3d(0.5, 0, 0), p() + Vector3d(0.5, 0, 0),
                           p() + Vector3d(0.5, 0, 0)};
    std::vector<Vector3d> samples_s, samples_t;
    for (int a = 0; a <= n; ++a) {
      for (int b = 0; a + b <= n; ++b) {
        const double wa = double(a) / n, wb = double(b) / n, wc = 1 - wa - wb;
        samples_s.push_back(wa * s.a + wb * s.b + wc * s.c);
        samples_t.push_back(wa * t.a + wb * t.b + wc * t.c);
      }
    }
    double sampled = HUGE_VAL;
    for (const Vector3d& x : samples_s) {
      for (const Vector3d& y : samples_t) sampled = std::min(sampled, (x - y).norm());
    }
    const double d = TriangleDistance(s, t);
    EXPECT_LE(d, sampled + 1e-12) << Describe(s, t);
    EXPECT_GE(d, sampled - 0.15) << "sampling too coarse or distance too small: " << Describe(s, t);
  }
}

}  // namespace
}  // namespace far
