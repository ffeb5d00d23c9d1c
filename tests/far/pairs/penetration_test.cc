// Penetration depth of closed meshes (far/pairs/penetration.h): which meshes are closed, the
// overlap of two boxes along the face normal, far from the origin, and random overlapping
// convex meshes against an independent reference (inside: strictly behind every face plane;
// depth: the nearest face plane), with the contact-seeded search equal to the all-vertex one.

#include "far/pairs/penetration.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_tests.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

using Eigen::Vector3d;

// An axis-aligned box [lo, hi] as 12 outward-facing triangles.
Mesh BoxMesh(const Vector3d& lo, const Vector3d& hi) {
  Mesh mesh;
  for (int k = 0; k < 8; ++k) {
    mesh.p_MV.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                           k & 4 ? hi.z() : lo.z());
  }
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return mesh;
}

WorldObjectView View(const Mesh& mesh) { return {mesh.p_MV, mesh.triangles}; }

bool Closed(const Mesh& mesh) { return IsClosedMesh(mesh.triangles, mesh.p_MV.size()); }

// Every intersecting triangle pair of a and b (what a step's contacts hold for the pair).
std::vector<ContactPair> AllContacts(const Mesh& a, const Mesh& b) {
  std::vector<ContactPair> contacts;
  for (uint32_t i = 0; i < a.triangles.size(); ++i) {
    for (uint32_t j = 0; j < b.triangles.size(); ++j) {
      const auto& ta = a.triangles[i];
      const auto& tb = b.triangles[j];
      if (TrianglesIntersect({a.p_MV[ta[0]], a.p_MV[ta[1]], a.p_MV[ta[2]]},
                             {b.p_MV[tb[0]], b.p_MV[tb[1]], b.p_MV[tb[2]]})) {
        contacts.push_back({0, i, 1, j});
      }
    }
  }
  return contacts;
}

Penetration Measure(const Mesh& a, const Mesh& b, bool seeded) {
  const PenetrationSurface sa(View(a)), sb(View(b));
  const std::vector<ContactPair> contacts = seeded ? AllContacts(a, b) : std::vector<ContactPair>{};
  return MeasurePenetration(sa, sb, contacts);
}

TEST(PenetrationTest, ClosedMeshesAreWatertightAndConsistentlyOriented) {
  const Mesh box = BoxMesh({0, 0, 0}, {1, 1, 1});
  EXPECT_TRUE(Closed(box));
  EXPECT_TRUE(Closed(scenes::SphereMesh({0, 0, 0}, 1, 6, 8)));
  Mesh hole = box;
  hole.triangles.pop_back();
  EXPECT_FALSE(Closed(hole));
  Mesh flipped = box;
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  EXPECT_FALSE(Closed(flipped));
  Mesh doubled = box;
  doubled.triangles.push_back(box.triangles[0]);
  EXPECT_FALSE(Closed(doubled));
  Mesh repeated_index = box;
  repeated_index.triangles[0] = {0, 0, 1};
  EXPECT_FALSE(Closed(repeated_index));
  // Two boxes sharing an edge: four triangles on that edge (non-manifold).
  Mesh two = box;
  const Mesh other = BoxMesh({1, 1, 0}, {2, 2, 1});
  const uint32_t shift = static_cast<uint32_t>(two.p_MV.size());
  two.p_MV.insert(two.p_MV.end(), other.p_MV.begin(), other.p_MV.end());
  for (TriangleIndices t : other.triangles) {
    for (uint32_t& v : t) v += shift;
    two.triangles.push_back(t);
  }
  EXPECT_TRUE(Closed(two));  // two separate shells: each edge still used twice
  // Merge the shared edge's vertices: (1, 1, 0) and (1, 1, 1) of both boxes.
  Mesh glued = two;
  for (TriangleIndices& t : glued.triangles) {
    for (uint32_t& v : t) {
      if (v == shift + 0) v = 3;  // other's (1, 1, 0) is box's vertex 3
      if (v == shift + 4) v = 7;  // other's (1, 1, 1) is box's vertex 7
    }
  }
  EXPECT_FALSE(Closed(glued));
  EXPECT_FALSE(IsClosedMesh({}, 0));
}

TEST(PenetrationTest, OverlappingBoxesGiveTheOverlapAlongTheFaceNormal) {
  // b overlaps a by 0.3 along x and is larger in y and z: a's four corners at x = 1 are inside
  // b, 0.3 from its face x = 0.7, and no corner of b is inside a.
  const Mesh a = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh b = BoxMesh({0.7, -0.5, -0.5}, {1.7, 1.5, 1.5});
  for (bool seeded : {false, true}) {
    const Penetration p = Measure(a, b, seeded);
    EXPECT_TRUE(p.closed);
    EXPECT_NEAR(p.depth, 0.3, 1e-15);
    EXPECT_EQ(p.direction, Vector3d(1, 0, 0));  // moving b along +x by 0.3 separates them
    EXPECT_EQ(p.point_a.x(), 1.0);              // a's corner
    EXPECT_EQ(p.point_b.x(), 0.7);              // on b's face
    EXPECT_EQ((p.point_a - p.point_b).norm(), p.depth);
  }
  // Touching face to face: nothing strictly inside.
  const Penetration touching = Measure(a, BoxMesh({1, 0, 0}, {2, 1, 1}), true);
  EXPECT_TRUE(touching.closed);
  EXPECT_EQ(touching.depth, 0.0);
  EXPECT_EQ(touching.direction, Vector3d::Zero());
  // Open meshes: no depth.
  Mesh open = b;
  open.triangles.pop_back();
  const Penetration none = MeasurePenetration(View(a), true, View(open), false);
  EXPECT_FALSE(none.closed);
  EXPECT_EQ(none.depth, 0.0);
}

TEST(PenetrationTest, ABoxInsideAnotherIsFoundThroughItsPartsRepresentative) {
  // No triangle pair intersects: the seeded search finds the inner box from the one vertex it
  // locates per connected part. Contacts elsewhere (a third box) do not hide it.
  const Mesh outer = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh inner = BoxMesh({0.4, 0.45, 0.5}, {0.6, 0.6, 0.6});
  const PenetrationSurface so(View(outer)), si(View(inner));
  const Penetration all = MeasurePenetration(so, si, {});
  const std::vector<ContactPair> unrelated = {{0, 0, 1, 0}};
  const Penetration seeded = MeasurePenetration(so, si, unrelated);
  EXPECT_NEAR(all.depth, 0.4, 1e-15);  // inner's corners at x = 0.6 and y = 0.6 are 0.4 in
  EXPECT_EQ(seeded.depth, all.depth);
  EXPECT_EQ(seeded.point_b, all.point_b);
}

TEST(PenetrationTest, FarFromTheOriginTheDecisionsHoldAndTheDepthStaysWithinItsBound) {
  for (double offset : {1e6, 1e9}) {
    const Vector3d o(offset, -offset, 0.5 * offset);
    const Mesh a = BoxMesh(o + Vector3d(0, 0, 0), o + Vector3d(1, 1, 1));
    const Mesh b = BoxMesh(o + Vector3d(0.75, -0.5, -0.5), o + Vector3d(1.75, 1.5, 1.5));
    const Penetration p = Measure(a, b, true);
    // The exact depth of the rounded input: a's face x = fl(o + 1) to b's x = fl(o + 0.75).
    const double exact = a.p_MV[1].x() - b.p_MV[0].x();
    const double bound = 128 * 0x1p-53 * 2 * offset;  // the distance bound, L <= 2 |o|
    EXPECT_TRUE(p.closed);
    EXPECT_NEAR(p.depth, exact, bound) << offset;
    EXPECT_NEAR(p.direction.x(), 1.0, 1e-12) << offset;
  }
}

// Reference for convex closed meshes with outward normals: v is strictly inside iff it is
// strictly behind every face plane (exact), and its distance to the surface is the smallest
// distance to a face plane.
double ConvexReferenceDepth(const Mesh& inner, const Mesh& outer) {
  double deepest = 0;
  for (const Vector3d& v : inner.p_MV) {
    bool inside = true;
    double nearest = HUGE_VAL;
    for (const TriangleIndices& t : outer.triangles) {
      const Vector3d &p0 = outer.p_MV[t[0]], &p1 = outer.p_MV[t[1]], &p2 = outer.p_MV[t[2]];
      if (internal::Collinear3d(p0, p1, p2)) continue;
      if (internal::Orient3d(p0, p1, p2, v) >= 0) {
        inside = false;
        break;
      }
      const Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
      nearest = std::min(nearest, std::abs(n.dot(v - p0)));
    }
    if (inside) deepest = std::max(deepest, nearest);
  }
  return deepest;
}

TEST(PenetrationTest, MatchesAConvexReferenceOnRandomOverlappingSpheres) {
  std::mt19937_64 rng(4343);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int overlapping = 0;
  for (int i = 0; i < 40; ++i) {
    const Vector3d offset = i % 2 == 0 ? Vector3d::Zero() : Vector3d(1e5, -2e5, 3e5);
    const Mesh a = scenes::SphereMesh(offset, 1.0, 8, 12);
    const Vector3d center = offset + 1.2 * Vector3d(u(rng), u(rng), u(rng));
    const Mesh b = scenes::SphereMesh(center, 0.3 + 0.7 * std::abs(u(rng)), 6, 10);
    ASSERT_TRUE(Closed(a) && Closed(b));
    const double reference = std::max(ConvexReferenceDepth(a, b), ConvexReferenceDepth(b, a));
    const Penetration all = Measure(a, b, false);
    const Penetration seeded = Measure(a, b, true);
    EXPECT_NEAR(all.depth, reference, 1e-9) << "case " << i;
    EXPECT_EQ(seeded.depth, all.depth) << "case " << i;
    overlapping += reference > 0;
  }
  EXPECT_GT(overlapping, 20);
}

}  // namespace
}  // namespace far
