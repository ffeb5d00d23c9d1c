#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "exact_reference.h"
#include "hard_cases.h"
#include "triangle_test_scenes.h"
#include <gtest/gtest.h>

#include "far/geometry/triangle_tests.h"

namespace far {
namespace {

using Eigen::Vector3d;
using reference::Describe;
using reference::ExactTrianglesIntersect;
using reference::Tri;

const TrianglePoints kBase = Tri(Vector3d(0, 0, 0), Vector3d(4, 0, 0), Vector3d(0, 4, 0));

TEST(TrianglesIntersectTest, CountsTouchingAsIntersecting) {
  // Shared vertex, shared edge, vertex on the face, edge crossing an edge.
  EXPECT_TRUE(
      TrianglesIntersect(kBase, Tri(Vector3d(4, 0, 0), Vector3d(5, 1, 1), Vector3d(5, -1, 2))));
  EXPECT_TRUE(
      TrianglesIntersect(kBase, Tri(Vector3d(0, 0, 0), Vector3d(4, 0, 0), Vector3d(2, 0, 3))));
  EXPECT_TRUE(
      TrianglesIntersect(kBase, Tri(Vector3d(1, 1, 0), Vector3d(0, 0, 2), Vector3d(3, 0, 2))));
  EXPECT_TRUE(TrianglesIntersect(Tri(Vector3d(0, 0, 0), Vector3d(4, 0, 0), Vector3d(2, -2, -2)),
                                 Tri(Vector3d(2, -1, 0), Vector3d(2, 1, 0), Vector3d(2, 0, 2))));
}

TEST(TrianglesIntersectTest, SeparatesByOneUlp) {
  const double above = std::nextafter(0.0 + 1.0, 2.0);
  const TrianglePoints lifted = Tri(Vector3d(0, 0, 1), Vector3d(4, 0, 1), Vector3d(0, 4, 1));
  const TrianglePoints touching = Tri(Vector3d(1, 1, 1), Vector3d(0, 0, 3), Vector3d(3, 0, 3));
  const TrianglePoints missing = Tri(Vector3d(1, 1, above), Vector3d(0, 0, 3), Vector3d(3, 0, 3));
  EXPECT_TRUE(TrianglesIntersect(lifted, touching));
  EXPECT_FALSE(TrianglesIntersect(lifted, missing));
}

TEST(TrianglesIntersectTest, TreatsDegenerateTrianglesAsSegmentsAndPoints) {
  const Vector3d p(1, 1, 0);
  EXPECT_TRUE(TrianglesIntersect(kBase, Tri(p, p, p)));
  const Vector3d q(1, 1, 1e-12);
  EXPECT_FALSE(TrianglesIntersect(kBase, Tri(q, q, q)));
  // A collinear triangle piercing the face, and one lying beside it.
  EXPECT_TRUE(
      TrianglesIntersect(kBase, Tri(Vector3d(1, 1, -1), Vector3d(1, 1, 2), Vector3d(1, 1, 0.5))));
  EXPECT_FALSE(TrianglesIntersect(
      kBase, Tri(Vector3d(-1, 1, -1), Vector3d(-1, 1, 2), Vector3d(-1, 1, 0.5))));
  // Two points.
  EXPECT_TRUE(TrianglesIntersect(Tri(p, p, p), Tri(p, p, p)));
  EXPECT_FALSE(TrianglesIntersect(Tri(p, p, p), Tri(q, q, q)));
}

// True iff the closed bounding boxes of s and t share a point (what TrianglesIntersectWithinBoxes
// takes as given).
bool BoxesTouch(const TrianglePoints& s, const TrianglePoints& t) {
  for (int k = 0; k < 3; ++k) {
    const double s_lo = std::min({s.a[k], s.b[k], s.c[k]}),
                 s_hi = std::max({s.a[k], s.b[k], s.c[k]});
    const double t_lo = std::min({t.a[k], t.b[k], t.c[k]}),
                 t_hi = std::max({t.a[k], t.b[k], t.c[k]});
    if (s_hi < t_lo || t_hi < s_lo) return false;
  }
  return true;
}

// Both entry points: TrianglesIntersect, and TrianglesIntersectWithinBoxes where it applies.
bool Answers(const TrianglePoints& s, const TrianglePoints& t, bool expected) {
  if (TrianglesIntersect(s, t) != expected) return false;
  return !BoxesTouch(s, t) || TrianglesIntersectWithinBoxes(s, t) == expected;
}

TEST(TrianglesIntersectTest, MatchesExactReferenceOnRandomizedScenes) {
  for (const reference::PairScene& scene : reference::MakePairScenes()) {
    std::mt19937_64 rng(20240601);
    std::uniform_int_distribution<int> relabel(0, 71);
    int disagreements = 0;
    int intersecting = 0;
    for (int i = 0; i < scene.count; ++i) {
      const auto [s, t] = scene.make(rng);
      const bool exact = ExactTrianglesIntersect(s, t);
      intersecting += exact;
      // The pair as drawn, and one random relabeling (vertex orders, swap).
      const auto relabelings = reference::Relabelings(s, t);
      const auto& [s2, t2] = relabelings[relabel(rng)];
      for (const auto& [a, b] : {std::make_pair(s, t), std::make_pair(s2, t2)}) {
        if (!Answers(a, b, exact)) {
          ++disagreements;
          ADD_FAILURE() << scene.name << " case " << i << ": exact " << exact << " for "
                        << Describe(a, b);
        }
      }
      if (disagreements > 5) break;
    }
    EXPECT_EQ(disagreements, 0) << scene.name;
    // Both answers must be well represented, or the scene tests little.
    EXPECT_GT(intersecting, scene.count / 20) << scene.name;
    EXPECT_LT(intersecting, scene.count - scene.count / 20) << scene.name;
  }
}

TEST(TrianglesIntersectTest, MatchesExactReferenceOnEveryHardCaseUnderAllRelabelings) {
  const std::vector<reference::HardCase> cases = reference::MakeHardCases();
  int checked = 0;
  int disagreements = 0;
  for (const reference::HardCase& c : cases) {
    for (const auto& [s, t] : reference::Relabelings(c.s, c.t)) {
      ++checked;
      if (!Answers(s, t, c.intersect)) {
        ++disagreements;
        if (disagreements <= 10) {
          ADD_FAILURE() << c.name << ": exact " << c.intersect << " for " << Describe(s, t);
        }
      }
    }
  }
  EXPECT_EQ(disagreements, 0) << "of " << checked;
  EXPECT_EQ(checked, 72 * static_cast<int>(cases.size()));
}

}  // namespace
}  // namespace far
