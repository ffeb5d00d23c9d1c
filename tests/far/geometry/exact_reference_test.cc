// Tests of the exact rational reference itself: it is the oracle for everything else, so it is
// checked against hand-computed answers and against the intent of every hard case.

#include "exact_reference.h"

#include <cmath>
#include <map>
#include <string>

#include "hard_cases.h"
#include <gtest/gtest.h>

namespace far::reference {
namespace {

using Eigen::Vector3d;

const TrianglePoints kUnit = Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0));

TEST(ExactReferenceTest, AnswersHandComputedIntersections) {
  // Piercing, touching at a vertex, parallel planes, coplanar disjoint.
  EXPECT_TRUE(ExactTrianglesIntersect(
      kUnit, Tri(Vector3d(0.2, 0.2, -1), Vector3d(0.2, 0.2, 1), Vector3d(0.3, 0.2, 0))));
  EXPECT_TRUE(
      ExactTrianglesIntersect(kUnit, Tri(Vector3d(1, 0, 0), Vector3d(2, 0, 1), Vector3d(2, 1, 1))));
  EXPECT_FALSE(
      ExactTrianglesIntersect(kUnit, Tri(Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1, 1))));
  EXPECT_FALSE(
      ExactTrianglesIntersect(kUnit, Tri(Vector3d(1, 1, 0), Vector3d(2, 1, 0), Vector3d(1, 2, 0))));
  // Degenerate: a point on the hypotenuse, a segment crossing the face, a point off it.
  const Vector3d mid(0.5, 0.5, 0);
  EXPECT_TRUE(ExactTrianglesIntersect(kUnit, Tri(mid, mid, mid)));
  EXPECT_TRUE(ExactTrianglesIntersect(
      kUnit, Tri(Vector3d(0.1, 0.1, -1), Vector3d(0.1, 0.1, 1), Vector3d(0.1, 0.1, 0.5))));
  const Vector3d off(0.5, 0.5, 1e-300);
  EXPECT_FALSE(ExactTrianglesIntersect(kUnit, Tri(off, off, off)));
}

TEST(ExactReferenceTest, AnswersHandComputedSquaredDistances) {
  // Parallel planes at height 2.
  EXPECT_EQ(
      ExactSquaredDistance(kUnit, Tri(Vector3d(0, 0, 2), Vector3d(1, 0, 2), Vector3d(0, 1, 2))), 4);
  // Skew edges: x axis segment vs a segment along y at z = 3 over x = 0.5.
  EXPECT_EQ(
      ExactSquaredDistance(Tri(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 0, -1)),
                           Tri(Vector3d(0.5, -1, 3), Vector3d(0.5, 1, 3), Vector3d(0.5, 0, 4))),
      9);
  // Vertex (0.25, 0.25, 0.5) above the face: distance 0.5.
  const Vector3d p(0.25, 0.25, 0.5);
  EXPECT_EQ(ExactSquaredDistance(kUnit, Tri(p, p, p)), mpq_class(1, 4));
  // Point beyond the hypotenuse corner (2, 0, 0): distance to (1, 0, 0) is 1.
  const Vector3d q(2, 0, 0);
  EXPECT_EQ(ExactSquaredDistance(kUnit, Tri(q, q, q)), 1);
  // Intersecting pairs are at distance 0.
  EXPECT_EQ(ExactSquaredDistance(kUnit, kUnit), 0);
}

TEST(ExactReferenceTest, AgreesWithTheIntentOfEveryHardCase) {
  const std::vector<HardCase> cases = MakeHardCases();
  int checked = 0;
  for (const HardCase& c : cases) {
    if (!c.intended) continue;
    ++checked;
    EXPECT_EQ(c.intersect, *c.intended) << c.name;
  }
  EXPECT_GT(checked, 300);
}

TEST(ExactReferenceTest, HardCasesStayInThePredicatesExactRange) {
  // far/internal/predicates.h: nonzero coordinates in [2^-300, 2^300], nonzero differences of
  // coordinates >= 2^-330. A case outside would test behaviour the library does not promise.
  const double lo = std::ldexp(1.0, -300), hi = std::ldexp(1.0, 300);
  for (const HardCase& c : MakeHardCases()) {
    const Vector3d* points[] = {&c.s.a, &c.s.b, &c.s.c, &c.t.a, &c.t.b, &c.t.c};
    for (const Vector3d* p : points) {
      for (int k = 0; k < 3; ++k) {
        const double x = std::abs((*p)[k]);
        ASSERT_TRUE(x == 0 || (x >= lo && x <= hi)) << c.name << ": " << x;
        for (const Vector3d* q : points) {
          const double d = std::abs((*p)[k] - (*q)[k]);
          ASSERT_TRUE(d == 0 || d >= std::ldexp(1.0, -330)) << c.name;
        }
      }
    }
  }
}

TEST(ExactReferenceTest, IsInvariantUnderRelabeling) {
  const std::vector<HardCase> cases = MakeHardCases();
  for (size_t i = 0; i < cases.size(); i += 3) {
    for (const auto& [s, t] : Relabelings(cases[i].s, cases[i].t)) {
      ASSERT_EQ(ExactTrianglesIntersect(s, t), cases[i].intersect) << cases[i].name;
    }
  }
}

TEST(ExactReferenceTest, HardCaseSuiteCoversEveryFamilyWithBothAnswers) {
  std::map<std::string, std::pair<int, int>> by_category;  // (intersecting, disjoint)
  for (const HardCase& c : MakeHardCases()) {
    auto& [yes, no] = by_category[c.category];
    (c.intersect ? yes : no) += 1;
  }
  for (const char* category : {"coplanar", "crossing", "shared", "vertex_face", "edge_edge",
                               "sliver", "collinear", "point"}) {
    ASSERT_TRUE(by_category.count(category)) << category;
    EXPECT_GT(by_category[category].first, 0) << category;
    EXPECT_GT(by_category[category].second, 0) << category;
  }
}

}  // namespace
}  // namespace far::reference
