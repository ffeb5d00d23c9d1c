// Penetration depth of closed meshes (far/pairs/penetration.h): which meshes are closed, the
// overlap of two boxes along the face normal, far from the origin, vertices exactly on the other
// surface and rays through edges, random overlapping convex meshes against an independent
// reference (inside: strictly behind every face plane; depth: the nearest face plane), and
// random non-convex meshes at random poses against a brute-force reference (inside: parity of
// crossings along random rays, over every triangle; depth: the nearest of every triangle), with
// the contact-seeded search equal to the all-vertex one.

#include "far/pairs/penetration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_tests.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

using Eigen::Vector3d;
using scenes::BoxMesh;

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
    EXPECT_EQ(p.point_a, Vector3d(1, 0, 0));    // a's corner with the smallest index
    EXPECT_EQ(p.point_b, Vector3d(0.7, 0, 0));  // on b's face
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
    // The distance bound (docs/contact-geometry.md): 128 u L, L the diagonal of the box around
    // the vertex and its nearest triangle (here at most 0.25 + 2 sqrt(2)): independent of |o|.
    const double bound = 128 * 0x1p-53 * (exact + 2 * std::sqrt(2.0));
    EXPECT_TRUE(p.closed);
    EXPECT_NEAR(p.depth, exact, bound) << offset;
    EXPECT_EQ(p.point_a, a.p_MV[1]) << offset;  // the corner of a with the smallest index
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

// A tetrahedron with apex `apex` and base triangle (p1, p2, p3), closed.
Mesh Tetrahedron(const Vector3d& apex, const Vector3d& p1, const Vector3d& p2, const Vector3d& p3) {
  Mesh mesh;
  mesh.p_MV = {apex, p1, p2, p3};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  return mesh;
}

// A tetrahedron pointing along -x with its apex at `apex` and its base at x = apex.x + 1.
Mesh Spike(const Vector3d& apex) {
  return Tetrahedron(apex, apex + Vector3d(1, -0.2, -0.2), apex + Vector3d(1, 0.3, -0.1),
                     apex + Vector3d(1, 0, 0.3));
}

TEST(PenetrationTest, AVertexExactlyOnTheOtherSurfaceIsNotInside) {
  const Mesh box = BoxMesh({0, 0, 0}, {1, 1, 1});
  // The apex on a face's interior, on the diagonal shared by the face's two triangles, on an
  // edge and on a corner of the box; the rest of the spike outside.
  for (const Vector3d& apex :
       {Vector3d(1, 0.25, 0.4), Vector3d(1, 0.5, 0.5), Vector3d(1, 1, 0.5), Vector3d(1, 1, 1)}) {
    const Mesh spike = Spike(apex);
    ASSERT_TRUE(Closed(spike));
    for (bool seeded : {false, true}) {
      const Penetration p = Measure(box, spike, seeded);
      EXPECT_TRUE(p.closed);
      EXPECT_EQ(p.depth, 0.0) << apex.transpose();
      EXPECT_EQ(p.direction, Vector3d::Zero());
      EXPECT_EQ(p.point_a, Vector3d::Zero());
      EXPECT_EQ(p.point_b, Vector3d::Zero());
    }
  }
}

TEST(PenetrationTest, AVertexWhoseFirstRayRunsThroughAnEdgeIsStillLocated) {
  // The apex (0.75, 0.5, 0.5): its ray along +x meets the face x = 1 on the diagonal its two
  // triangles share (y + z = 1), a degenerate ray; the next one decides. Then the apex at
  // (0.75, 0, 0.5): its ray runs in the face plane y = 0 (on the surface? no: x < 1 is inside
  // the face, so the apex IS on the surface). Then y = 0.5, z = 0 likewise on the surface.
  const Mesh box = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Penetration p = Measure(box, Spike({0.75, 0.5, 0.5}), false);
  EXPECT_EQ(p.depth, 0.25);
  EXPECT_EQ(p.point_b, Vector3d(0.75, 0.5, 0.5));  // the spike's apex, inside the box
  EXPECT_EQ(p.point_a, Vector3d(1, 0.5, 0.5));     // on the box's face
  EXPECT_EQ(p.direction, Vector3d(1, 0, 0));       // moving the spike by +0.25 x frees it
  // Rays through a vertex: a box whose face x = 1 is split at its center (an octahedral cap
  // would do as well); the apex (0.75, 0.5, 0.5) looks straight at the new vertex.
  Mesh split = box;
  split.p_MV.emplace_back(1, 0.5, 0.5);                                        // vertex 8
  split.triangles.erase(split.triangles.begin() + 10, split.triangles.end());  // x = 1 face
  for (TriangleIndices t : {TriangleIndices{1, 3, 8}, TriangleIndices{3, 7, 8},
                            TriangleIndices{7, 5, 8}, TriangleIndices{5, 1, 8}}) {
    split.triangles.push_back(t);
  }
  ASSERT_TRUE(Closed(split));
  const Penetration q = Measure(split, Spike({0.75, 0.5, 0.5}), true);
  EXPECT_EQ(q.depth, 0.25);
  EXPECT_EQ(q.point_a, Vector3d(1, 0.5, 0.5));
  // The apex on the face plane y = 0 but inside the face: on the surface.
  EXPECT_EQ(Measure(box, Spike({0.75, 0, 0.5}), false).depth, 0.0);
}

TEST(PenetrationTest, ARodThroughAWallGetsItsTipDepthNotTheSeparatingDistance) {
  // What docs/contact-geometry.md says the number is not: the rod's tip is 0.1 from the far
  // face, so depth = 0.1 toward it, though separating the objects takes 0.5 sideways.
  const Mesh box = BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh rod = BoxMesh({-1, 0.49, 0.49}, {0.9, 0.51, 0.51});
  const Penetration p = Measure(box, rod, true);
  EXPECT_NEAR(p.depth, 0.1, 1e-15);
  EXPECT_EQ(p.direction, Vector3d(1, 0, 0));
  EXPECT_EQ(p.point_b.x(), 0.9);  // a vertex of the rod's tip
}

// The brute-force reference: `v` strictly inside `mesh` by the parity of a segment's crossings
// with every triangle, the segment's far end in a random direction (a new one whenever an
// orientation is zero); on the surface (not inside) when the point lies on a triangle.
bool BruteForceInside(const Mesh& mesh, const Vector3d& v, std::mt19937_64& rng) {
  for (const TriangleIndices& t : mesh.triangles) {
    if (TrianglesIntersect({v, v, v}, {mesh.p_MV[t[0]], mesh.p_MV[t[1]], mesh.p_MV[t[2]]})) {
      return false;
    }
  }
  Eigen::AlignedBox3d box;
  for (const Vector3d& p : mesh.p_MV) box.extend(p);
  const double reach = 2 * (box.diagonal().norm() + (v - box.center()).norm()) + 1;
  std::normal_distribution<double> gauss;
  for (;;) {
    const Vector3d w = v + reach * Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    int crossings = 0;
    bool degenerate = false;
    for (const TriangleIndices& t : mesh.triangles) {
      const Vector3d &a = mesh.p_MV[t[0]], &b = mesh.p_MV[t[1]], &c = mesh.p_MV[t[2]];
      if (internal::Collinear3d(a, b, c)) continue;
      const int sv = internal::Orient3d(a, b, c, v), sw = internal::Orient3d(a, b, c, w);
      if (sv == 0 || sw == 0) {
        degenerate = true;
        break;
      }
      if (sv == sw) continue;
      const int o1 = internal::Orient3d(v, w, a, b), o2 = internal::Orient3d(v, w, b, c),
                o3 = internal::Orient3d(v, w, c, a);
      if (o1 == 0 || o2 == 0 || o3 == 0) {
        degenerate = true;
        break;
      }
      crossings += o1 == o2 && o2 == o3;
    }
    if (!degenerate) return crossings % 2 == 1;
  }
}

struct Reference {
  double depth = -1;
  Vector3d vertex = Vector3d::Zero();
};

// The deepest vertex of `inner` strictly inside `outer` and its distance to every triangle of
// `outer` (ties: the smallest vertex index, as MeasurePenetration).
Reference BruteForceDeepest(const Mesh& inner, const Mesh& outer, std::mt19937_64& rng) {
  Reference deepest;
  for (const Vector3d& v : inner.p_MV) {
    if (!BruteForceInside(outer, v, rng)) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (const TriangleIndices& t : outer.triangles) {
      nearest = std::min(nearest, TriangleDistance({v, v, v}, {outer.p_MV[t[0]], outer.p_MV[t[1]],
                                                               outer.p_MV[t[2]]}));
    }
    if (nearest > deepest.depth) deepest = {nearest, v};
  }
  return deepest;
}

// A closed non-convex mesh: a UV sphere with every vertex moved along its ray from the center by
// a random factor in [0.55, 1.15] (star-shaped, so it does not pass through itself).
Mesh BumpySphere(double radius, int stacks, int slices, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> factor(0.55, 1.15);
  Mesh mesh = scenes::SphereMesh({0, 0, 0}, radius, stacks, slices);
  for (Vector3d& p : mesh.p_MV) p *= factor(rng);
  return mesh;
}

Mesh Posed(Mesh mesh, const Eigen::Quaterniond& rotation, const Vector3d& translation) {
  for (Vector3d& p : mesh.p_MV) p = rotation * p + translation;
  return mesh;
}

TEST(PenetrationTest, MatchesABruteForceReferenceOnRandomNonConvexMeshesAtRandomPoses) {
  std::mt19937_64 rng(4344);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> gauss;
  const auto random_rotation = [&] {
    return Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized();
  };
  int overlapping = 0;
  for (int i = 0; i < 36; ++i) {
    const double offset = std::array{0.0, 1e6, 1e9}[i % 3];
    const Vector3d origin = offset * Vector3d(1, -0.5, 0.25);
    const Mesh a = Posed(BumpySphere(1.0, 7, 11, rng), random_rotation(), origin);
    const Mesh b = i % 2 == 0
                       ? Posed(BumpySphere(0.6, 5, 8, rng), random_rotation(),
                               origin + 1.3 * Vector3d(u(rng), u(rng), u(rng)))
                       : Posed(BoxMesh({-0.4, -0.3, -0.5}, {0.4, 0.3, 0.5}), random_rotation(),
                               origin + 1.2 * Vector3d(u(rng), u(rng), u(rng)));
    ASSERT_TRUE(Closed(a) && Closed(b));
    const Reference b_in_a = BruteForceDeepest(b, a, rng);
    const Reference a_in_b = BruteForceDeepest(a, b, rng);
    const Penetration all = Measure(a, b, false);
    const Penetration seeded = Measure(a, b, true);
    const Penetration by_view = MeasurePenetration(View(a), true, View(b), true);
    const double depth = std::max({0.0, b_in_a.depth, a_in_b.depth});
    EXPECT_EQ(all.depth, depth) << "case " << i;
    EXPECT_EQ(seeded.depth, all.depth) << "case " << i;
    EXPECT_EQ(by_view.depth, all.depth) << "case " << i;
    EXPECT_EQ(seeded.point_a, all.point_a) << "case " << i;
    EXPECT_EQ(seeded.point_b, all.point_b) << "case " << i;
    if (depth > 0) {
      ++overlapping;
      // The witness: b's vertex inside a (b wins ties), or a's inside b; the other point is on
      // the other surface, depth away (up to the closest point's rounding, 64 u M).
      const bool b_deeper = b_in_a.depth >= a_in_b.depth;
      EXPECT_EQ(b_deeper ? all.point_b : all.point_a, b_deeper ? b_in_a.vertex : a_in_b.vertex)
          << "case " << i;
      const double point_bound = 256 * 0x1p-53 * (offset + 4);
      EXPECT_NEAR((all.point_a - all.point_b).norm(), depth, point_bound) << "case " << i;
      EXPECT_NEAR(all.direction.norm(), 1.0, 1e-12);
    } else {
      EXPECT_EQ(all.direction, Vector3d::Zero());
    }
  }
  EXPECT_GT(overlapping, 18);
}

TEST(PenetrationTest, ATetrahedronPokingASphereGivesItsApexDepth) {
  const Mesh sphere = scenes::SphereMesh({0, 0, 0}, 1.0, 24, 32);
  ASSERT_TRUE(Closed(sphere));
  std::mt19937_64 rng(4345);
  for (const Vector3d& apex :
       {Vector3d(0.8, 0.1, 0.05), Vector3d(0.95, -0.02, 0.1), Vector3d(0.5, 0.0, 0.0)}) {
    const Mesh spike = Spike(apex);
    ASSERT_TRUE(Closed(spike));
    const Reference reference = BruteForceDeepest(spike, sphere, rng);
    for (bool seeded : {false, true}) {
      const Penetration p = Measure(sphere, spike, seeded);
      EXPECT_EQ(p.depth, reference.depth) << apex.transpose();
      EXPECT_EQ(p.point_b, apex);  // the spike's apex is the only vertex inside
      // The polyhedral sphere is a little inside the unit sphere: the depth is at most 1 - |v|.
      EXPECT_LE(p.depth, 1 - apex.norm());
      EXPECT_GT(p.depth, 1 - apex.norm() - 0.01);
      // Its direction points out of the sphere, about along the apex's ray.
      EXPECT_GT(p.direction.dot(apex.normalized()), 0.99);
    }
  }
}

}  // namespace
}  // namespace far
