// Exact closed triangle-triangle intersection (touching counts).
//
// Every decision is the sign of an orientation determinant of input points (Orient3d,
// Orient2d: exact, see predicates.h) or a comparison of input coordinates, so the answer is
// exact for the double input; no point is ever constructed.
//
// General position follows Guigue and Devillers ("Fast and robust triangle-triangle overlap
// test using orientation predicates", JGT 8(1), 2003): classify each triangle's vertices
// against the other's plane, then compare the two intervals that the triangles cut from the
// line where the planes meet, with two more orientations. Pairs where a sign triple is all zero
// (coplanar pairs and degenerate triangles) go to a slow path that projects onto a coordinate
// plane chosen exactly and runs exact 2D tests, or treats a degenerate triangle as the segment
// or point it is.
//
// Derivation of the general-position test (kept here because the sign bookkeeping is subtle).
// Let n_S, n_T be the right-handed normals, d = n_S x n_T the direction of L = plane(S) ^
// plane(T). Pick an apex v of S such that both other vertices w are strictly on one side of
// the level of v w.r.t. plane(T): eps_S = -sign(n_T . (w - v)). Then S ^ L = [i1, i2] with
// i1 on edge (v, w1), i2 on edge (v, w2) (both equal to v when v is on plane(T)), and with
// (v, w1, w2) in S's cyclic order, i2 - i1 has the sign -eps_S along d. For an edge (v, w) of
// S through i and an edge (u, z) of T through k:
//   Orient3d(v, w, u, z) = -sign(((w - v) x (z - u)) . (k - i)) = eps_S eps_T sign((k - i) . d)
// because ((w - v) x (z - u)) . d = -(n_T . (w - v)) (n_S . (z - u)). Reversing T's vertex
// order flips n_T (hence eps_S and d) and reversing S's flips eps_T, so after relabelling both
// apexes have eps = +1, and then S ^ L = [i2, i1], T ^ L = [k1, k2] along d, which meet iff
//   Orient3d(v, w1, u, z1) <= 0  and  Orient3d(v, w2, u, z2) >= 0.

#include <algorithm>
#include <array>

#include "triangle_shapes.h"
#include <Eigen/Geometry>

#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_tests.h"

namespace far {
namespace {

using Eigen::Vector3d;
using internal::Collinear3d;
using internal::Orient2d;
using internal::Orient2dProjected;
using internal::Orient3d;
using internal::PlaneSide;
using namespace internal;  // NOLINT: the shared blocks of triangle_shapes.h

// --- Small exact helpers -------------------------------------------------------------------

// Closed segments [a, b] and [c, d] in the plane; either may be a single point.
bool SegmentsIntersect2d(const P2& a, const P2& b, const P2& c, const P2& d) {
  const int o1 = Orient(a, b, c);
  const int o2 = Orient(a, b, d);
  const int o3 = Orient(c, d, a);
  const int o4 = Orient(c, d, b);
  // Proper crossing.
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  // Otherwise they meet only if an endpoint of one lies on the other.
  if (o1 == 0 && WithinBox2(a, b, c)) return true;
  if (o2 == 0 && WithinBox2(a, b, d)) return true;
  if (o3 == 0 && WithinBox2(c, d, a)) return true;
  if (o4 == 0 && WithinBox2(c, d, b)) return true;
  return false;
}

// Closed segment [a, b] (possibly a point) against a closed non-degenerate triangle in the plane.
bool SegmentTriangle2d(const P2& a, const P2& b, const std::array<P2, 3>& t, int orientation) {
  if (PointInTriangle2d(a, t[0], t[1], t[2], orientation)) return true;
  if (PointInTriangle2d(b, t[0], t[1], t[2], orientation)) return true;
  for (int i = 0; i < 3; ++i) {
    if (SegmentsIntersect2d(a, b, t[i], t[(i + 1) % 3])) return true;
  }
  return false;
}

// Closed non-degenerate triangles in the plane.
bool TrianglesIntersect2d(const std::array<P2, 3>& s, int s_orientation, const std::array<P2, 3>& t,
                          int t_orientation) {
  // Two convex polygons meet iff an edge of one crosses an edge of the other or one contains
  // the other (then it contains all of the other's vertices, so testing one vertex suffices).
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (SegmentsIntersect2d(s[i], s[(i + 1) % 3], t[j], t[(j + 1) % 3])) return true;
    }
  }
  return PointInTriangle2d(s[0], t[0], t[1], t[2], t_orientation) ||
         PointInTriangle2d(t[0], s[0], s[1], s[2], s_orientation);
}

// Closed segments [a, b], [c, d] in space; a != b and c != d.
bool SegmentSegment3d(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  if (Orient3d(a, b, c, d) != 0) return false;  // skew lines never meet
  // Coplanar: find three of the points that span the plane and project along an axis that the
  // plane is not parallel to.
  const std::array<std::array<const Vector3d*, 3>, 4> triples = {
      {{&a, &b, &c}, {&a, &b, &d}, {&a, &c, &d}, {&b, &c, &d}}};
  for (const auto& tri : triples) {
    if (Collinear3d(*tri[0], *tri[1], *tri[2])) continue;
    const Projection proj = ChooseProjection(*tri[0], *tri[1], *tri[2]);
    return SegmentsIntersect2d(Project(a, proj.i, proj.j), Project(b, proj.i, proj.j),
                               Project(c, proj.i, proj.j), Project(d, proj.i, proj.j));
  }
  // All four points on one line: compare the intervals along an axis where a != b (the line is
  // not perpendicular to it, so the projection is one-to-one on the line).
  int k = 0;
  while (k < 2 && a[k] == b[k]) ++k;
  return std::max(std::min(a[k], b[k]), std::min(c[k], d[k])) <=
         std::min(std::max(a[k], b[k]), std::max(c[k], d[k]));
}

// Closed segment [a, b] (a != b) against the closed non-degenerate triangle t.
bool SegmentTriangle3d(const Vector3d& a, const Vector3d& b, const TrianglePoints& t) {
  const PlaneSide plane(t.a, t.b, t.c);
  const int side_a = plane.Side(a);
  const int side_b = plane.Side(b);
  if (side_a == side_b && side_a != 0) return false;
  if (side_a == 0 && side_b == 0) {
    const Projection proj = ChooseProjection(t.a, t.b, t.c);
    const std::array<P2, 3> t2 = {Project(t.a, proj.i, proj.j), Project(t.b, proj.i, proj.j),
                                  Project(t.c, proj.i, proj.j)};
    return SegmentTriangle2d(Project(a, proj.i, proj.j), Project(b, proj.i, proj.j), t2,
                             proj.orientation);
  }
  // The segment crosses the plane at one point X. Orient3d(a, b, q_i, q_j) has the sign of
  // ((b - a) . n_T) times the orientation of (X, q_i, q_j) in the plane, so X is in the closed
  // triangle iff the three signs do not disagree.
  const int o0 = Orient3d(a, b, t.a, t.b);
  const int o1 = Orient3d(a, b, t.b, t.c);
  const int o2 = Orient3d(a, b, t.c, t.a);
  return (o0 >= 0 && o1 >= 0 && o2 >= 0) || (o0 <= 0 && o1 <= 0 && o2 <= 0);
}

// Slow path: one of the sign triples was all zero, so the triangles are coplanar or at least
// one of them is degenerate.
bool CoplanarOrDegenerate(const TrianglePoints& s, const TrianglePoints& t) {
  const Shape shape_s = Classify(s);
  const Shape shape_t = Classify(t);
  if (shape_s.kind == Shape::kTriangle && shape_t.kind == Shape::kTriangle) {
    // Both non-degenerate with an all-zero sign triple: coplanar.
    const Projection proj = ChooseProjection(s.a, s.b, s.c);
    const std::array<P2, 3> s2 = {Project(s.a, proj.i, proj.j), Project(s.b, proj.i, proj.j),
                                  Project(s.c, proj.i, proj.j)};
    const std::array<P2, 3> t2 = {Project(t.a, proj.i, proj.j), Project(t.b, proj.i, proj.j),
                                  Project(t.c, proj.i, proj.j)};
    const int t_orientation = Orient(t2[0], t2[1], t2[2]);
    return TrianglesIntersect2d(s2, proj.orientation, t2, t_orientation);
  }
  // Make s the "larger" shape: triangle > segment > point.
  const TrianglePoints* tri = &s;
  Shape big = shape_s;
  Shape small = shape_t;
  if (shape_t.kind < shape_s.kind) {
    tri = &t;
    big = shape_t;
    small = shape_s;
  }
  switch (big.kind) {
    case Shape::kTriangle:
      if (small.kind == Shape::kSegment) return SegmentTriangle3d(small.p, small.q, *tri);
      return PointTriangle3d(small.p, *tri);
    case Shape::kSegment:
      if (small.kind == Shape::kSegment) return SegmentSegment3d(big.p, big.q, small.p, small.q);
      return PointOnSegment3d(small.p, big.p, big.q);
    case Shape::kPoint:
      return big.p == small.p;
  }
  return false;
}

inline bool BoxesDisjoint(const TrianglePoints& s, const TrianglePoints& t) {
  const Eigen::Array3d s_min = s.a.array().min(s.b.array()).min(s.c.array());
  const Eigen::Array3d s_max = s.a.array().max(s.b.array()).max(s.c.array());
  const Eigen::Array3d t_min = t.a.array().min(t.b.array()).min(t.c.array());
  const Eigen::Array3d t_max = t.a.array().max(t.b.array()).max(t.c.array());
  return ((s_max < t_min) || (t_max < s_min)).any();
}

// The exact test without the bounding-box early-out.
bool IntersectAfterBoxTest(const TrianglePoints& s, const TrianglePoints& t) {
  // Signs of s's vertices w.r.t. the plane of t.
  const PlaneSide plane_t(t.a, t.b, t.c);
  const std::array<int, 3> sigma = {plane_t.Side(s.a), plane_t.Side(s.b), plane_t.Side(s.c)};
  if (sigma[0] == sigma[1] && sigma[1] == sigma[2]) {
    if (sigma[0] != 0) return false;    // s strictly on one side
    return CoplanarOrDegenerate(s, t);  // t degenerate, or s in t's plane
  }
  // Signs of t's vertices w.r.t. the plane of s. Now t is known to be non-degenerate.
  const PlaneSide plane_s(s.a, s.b, s.c);
  const std::array<int, 3> tau = {plane_s.Side(t.a), plane_s.Side(t.b), plane_s.Side(t.c)};
  if (tau[0] == tau[1] && tau[1] == tau[2]) {
    if (tau[0] != 0) return false;
    return CoplanarOrDegenerate(s, t);  // s degenerate
  }
  // General position: both triangles non-degenerate, their planes meet in a line L that both
  // triangles touch. Compare the two intervals on L (derivation at the top of this file).
  const ApexLabels l = LabelApexes(s, t, sigma, tau);
  return Orient3d(*l.v, *l.w1, *l.u, *l.z1) <= 0 && Orient3d(*l.v, *l.w2, *l.u, *l.z2) >= 0;
}

}  // namespace

bool TrianglesIntersect(const TrianglePoints& s, const TrianglePoints& t) {
  // Cheap early-out: disjoint bounding boxes (exact comparisons of input coordinates).
  if (BoxesDisjoint(s, t)) return false;
  return IntersectAfterBoxTest(s, t);
}

bool TrianglesIntersectWithinBoxes(const TrianglePoints& s, const TrianglePoints& t) {
  return IntersectAfterBoxTest(s, t);
}

}  // namespace far
