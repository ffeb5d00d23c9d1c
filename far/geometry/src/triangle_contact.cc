// Where two intersecting triangles meet: TriangleContactGeometry.
//
// The intersection of two closed triangles is convex, and each of its extreme points is one of
//   - a vertex of one triangle that lies in the other,
//   - the point where an edge of one crosses the other's plane (edge not in that plane),
//   - the point where two coplanar edges cross properly.
// Which of these candidates are the answer is decided with the exact predicates only, as in the
// intersection test (triangle_intersection.cc): in general position by Guigue and Devillers'
// interval comparison on the line L where the planes meet (the same four orientations order
// the ends of the two intervals), for coplanar pairs by exact 2D tests in a projection, for
// degenerate triangles by what they are (segment or point). Coincidence is decided exactly too,
// so "one point" means the triangles touch at exactly one point.
//
// Construction. A constructed point lies on an input segment [p, q]: X = p + t (q - p) with
// t = dp / (dp - dq), where dp and dq are the signed values, at p and q, of the orientation
// determinant that decided the crossing (Orient3dValue against a plane, or Orient2dValue
// against a line in the projection; both within 2^-51 relative, from exact expansions when the
// floating-point value cannot be certified). dp and dq have opposite signs, so t has no
// cancellation: it is within 6u relative (u = 2^-53), and the point is built from the nearer
// end (t <= 1/2) so that the error scales with t. Per coordinate, with M the largest magnitude
// of the two triangles' coordinates: |q - p| <= 2M, so
//   |X~ - X| <= |q - p| (|dt| + t (2u)) + u |X| <= 2M (3u + u) + u M = 9 u M
// to first order; docs/culling.md states 16 u M. Ends are exact: dp == 0 gives p itself.
// Vertices are returned as they are. Only the order of a coplanar polygon's vertices is read
// from the rounded points (a polygon whose vertices lie within the error bound may be listed in
// another order than the exact one).

#include "far/geometry/triangle_contact.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include "triangle_shapes.h"
#include <Eigen/Geometry>

#include "far/geometry/internal/predicates.h"

namespace far {
namespace {

using Eigen::Vector3d;
using namespace internal;  // NOLINT: the shared blocks of triangle_shapes.h

// The point of [p, q] where an affine function with values dp at p and dq at q vanishes.
// @pre dp and dq do not have the same strict sign; not both zero.
Vector3d PointBetween(const Vector3d& p, const Vector3d& q, double dp, double dq) {
  if (dp == 0.0) return p;
  if (dq == 0.0) return q;
  const double ap = std::abs(dp);
  const double aq = std::abs(dq);
  if (ap <= aq) return p + (ap / (ap + aq)) * (q - p);
  return q + (aq / (ap + aq)) * (p - q);
}

// Where the segment [p, q] crosses `plane`. @pre p and q not strictly on one side.
Vector3d EdgePlaneCrossing(const Vector3d& p, const Vector3d& q, const PlaneValue& plane) {
  return PointBetween(p, q, plane.Value(p), plane.Value(q));
}

// Where the segment [p, q] crosses the line through r and s, all in one plane seen through the
// projection (i, j). @pre they cross (or touch) in the projection.
Vector3d EdgeLineCrossing(const Vector3d& p, const Vector3d& q, const Vector3d& r,
                          const Vector3d& s, int i, int j) {
  return PointBetween(p, q, Orient2dValue(r[i], r[j], s[i], s[j], p[i], p[j]),
                      Orient2dValue(r[i], r[j], s[i], s[j], q[i], q[j]));
}

// True when [a, b] and [c, d] cross at one point interior to both (coplanar, projected).
inline bool ProperCrossing2d(const P2& a, const P2& b, const P2& c, const P2& d) {
  return Orient(a, b, c) * Orient(a, b, d) < 0 && Orient(c, d, a) * Orient(c, d, b) < 0;
}

// The candidate points of one intersection, without exact duplicates of input vertices.
class Candidates {
 public:
  // Adds an input vertex unless it is already there (the same coordinates).
  void AddVertex(const Vector3d& p) {
    for (int k = 0; k < count_; ++k) {
      if (points_[k] == p) return;
    }
    Add(p);
  }
  // Adds a constructed point (callers ensure it is distinct from the others).
  void Add(const Vector3d& p) {
    if (count_ < static_cast<int>(points_.size())) points_[count_++] = p;
  }
  int count() const { return count_; }
  const Vector3d& operator[](int k) const { return points_[k]; }

  // Writes the two candidates farthest apart (or the only one): the intersection is a segment
  // or point through all of them.
  void WriteExtremes(ContactGeometry& out) const {
    int best_i = 0, best_j = 0;
    double best = -1.0;
    for (int i = 0; i < count_; ++i) {
      for (int j = i + 1; j < count_; ++j) {
        const double d = (points_[i] - points_[j]).squaredNorm();
        if (d > best) {
          best = d;
          best_i = i;
          best_j = j;
        }
      }
    }
    out.points[0] = points_[best_i];
    out.num_points = 1;
    if (count_ > 1) {
      out.points[1] = points_[best_j];
      out.num_points = 2;
    }
  }

 private:
  // 3 + 3 vertices and at most 6 proper crossings of two triangles' boundaries.
  std::array<Vector3d, 12> points_;
  int count_ = 0;
};

// The unit normal of t, zero exactly when t is degenerate (RoundedCross is zero exactly when
// b - a and c - a are parallel, that is when the corners are collinear or coincide).
Vector3d UnitNormal(const TrianglePoints& t) {
  const Vector3d n = RoundedCross(t.a, t.b, t.a, t.c);
  const double largest = n.cwiseAbs().maxCoeff();
  if (largest == 0.0) return Vector3d::Zero();
  const Vector3d scaled = n / largest;  // no overflow or underflow in the norm
  return scaled / scaled.norm();
}

// --- General position -----------------------------------------------------------------------

// Both triangles non-degenerate, their planes meeting in a line L that both touch. Follows the
// interval comparison of IntersectAfterBoxTest (its derivation is at the top of
// triangle_intersection.cc): after relabelling, S ^ L = [i2, i1] and T ^ L = [k1, k2] along d,
// with i1 on edge (v, w1), i2 on (v, w2), k1 on (u, z1), k2 on (u, z2), and for a, b in {1, 2}
// sign((k_b - i_a) . d) = Orient3d(v, w_a, u, z_b). The intersection is [max(i2, k1),
// min(i1, k2)].
void GeneralPosition(const TrianglePoints& s, const TrianglePoints& t,
                     const std::array<int, 3>& sigma, const std::array<int, 3>& tau,
                     ContactGeometry& out) {
  const ApexLabels l = LabelApexes(s, t, sigma, tau);
  const Vector3d &v = *l.v, &u = *l.u;
  const Vector3d *w1 = l.w1, *w2 = l.w2, *z1 = l.z1, *z2 = l.z2;

  // The lower end: k1 when it lies beyond i2 along d, else i2 (equal when the sign is 0).
  const bool lower_is_k1 = Orient3d(v, *w2, u, *z1) > 0;
  // The upper end: k2 when it lies before i1, else i1.
  const bool upper_is_k2 = Orient3d(v, *w1, u, *z2) < 0;
  // Whether the two ends coincide: decided for the pair of points they are.
  bool single;
  if (!lower_is_k1 && !upper_is_k2) {
    single = sigma[l.apex_s] == 0;  // i2 == i1: v lies on T's plane
  } else if (lower_is_k1 && upper_is_k2) {
    single = tau[l.apex_t] == 0;  // k1 == k2: u lies on S's plane
  } else if (lower_is_k1) {
    single = Orient3d(v, *w1, u, *z1) == 0;  // k1 == i1
  } else {
    single = Orient3d(v, *w2, u, *z2) == 0;  // i2 == k2
  }
  const PlaneValue value_s(s.a, s.b, s.c), value_t(t.a, t.b, t.c);
  out.points[0] =
      lower_is_k1 ? EdgePlaneCrossing(u, *z1, value_s) : EdgePlaneCrossing(v, *w2, value_t);
  out.num_points = 1;
  if (!single) {
    out.points[1] =
        upper_is_k2 ? EdgePlaneCrossing(u, *z2, value_s) : EdgePlaneCrossing(v, *w1, value_t);
    out.num_points = 2;
  }
}

// --- Coplanar triangles ---------------------------------------------------------------------

// Whether the coplanar triangles' common part has no area: an edge line of one has the whole
// other triangle on its closed outer side (for convex polygons a separating line, if any, can
// be taken along an edge).
bool TouchOnly(const std::array<P2, 3>& s, int s_orientation, const std::array<P2, 3>& t,
               int t_orientation) {
  for (int pass = 0; pass < 2; ++pass) {
    const auto& a = pass == 0 ? s : t;
    const auto& b = pass == 0 ? t : s;
    const int orientation = pass == 0 ? s_orientation : t_orientation;
    for (int i = 0; i < 3; ++i) {
      bool outside = true;
      for (int j = 0; j < 3 && outside; ++j) {
        outside = Orient(a[i], a[(i + 1) % 3], b[j]) * orientation <= 0;
      }
      if (outside) return true;
    }
  }
  return false;
}

// Writes a convex polygon's vertices counterclockwise seen from the projection's +k axis
// (reversed when `reverse`), as the convex hull of the rounded candidates (Andrew's monotone
// chain; vertices that rounding left on or inside the hull are dropped).
void WritePolygon(const Candidates& c, int i, int j, bool reverse, ContactGeometry& out) {
  std::array<int, 12> order;
  const int n = c.count();
  for (int k = 0; k < n; ++k) order[k] = k;
  std::sort(order.begin(), order.begin() + n, [&](int x, int y) {
    return c[x][i] < c[y][i] || (c[x][i] == c[y][i] && c[x][j] < c[y][j]);
  });
  auto turn = [&](int a, int b, int d) {
    return Orient2d(c[a][i], c[a][j], c[b][i], c[b][j], c[d][i], c[d][j]);
  };
  std::array<int, 24> hull;
  int h = 0;
  for (int k = 0; k < n; ++k) {  // lower hull
    while (h >= 2 && turn(hull[h - 2], hull[h - 1], order[k]) <= 0) --h;
    hull[h++] = order[k];
  }
  for (int k = n - 2, lower = h + 1; k >= 0; --k) {  // upper hull
    while (h >= lower && turn(hull[h - 2], hull[h - 1], order[k]) <= 0) --h;
    hull[h++] = order[k];
  }
  --h;          // the first point closes the chain
  if (h < 3) {  // rounding flattened it: report the extremes
    c.WriteExtremes(out);
    return;
  }
  h = std::min(h, ContactGeometry::kMaxPoints);
  for (int k = 0; k < h; ++k) out.points[k] = c[hull[reverse ? h - 1 - k : k]];
  out.num_points = h;
}

void Coplanar(const TrianglePoints& s, const TrianglePoints& t, ContactGeometry& out) {
  out.coplanar = true;
  const Projection proj = ChooseProjection(s.a, s.b, s.c);
  const int i = proj.i, j = proj.j;
  const std::array<const Vector3d*, 3> sv = {&s.a, &s.b, &s.c};
  const std::array<const Vector3d*, 3> tv = {&t.a, &t.b, &t.c};
  const std::array<P2, 3> s2 = {Project(s.a, i, j), Project(s.b, i, j), Project(s.c, i, j)};
  const std::array<P2, 3> t2 = {Project(t.a, i, j), Project(t.b, i, j), Project(t.c, i, j)};
  const int t_orientation = Orient(t2[0], t2[1], t2[2]);
  Candidates c;
  for (int k = 0; k < 3; ++k) {
    if (PointInTriangle2d(s2[k], t2[0], t2[1], t2[2], t_orientation)) c.AddVertex(*sv[k]);
    if (PointInTriangle2d(t2[k], s2[0], s2[1], s2[2], proj.orientation)) c.AddVertex(*tv[k]);
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (ProperCrossing2d(s2[a], s2[(a + 1) % 3], t2[b], t2[(b + 1) % 3])) {
        c.Add(EdgeLineCrossing(*sv[a], *sv[(a + 1) % 3], *tv[b], *tv[(b + 1) % 3], i, j));
      }
    }
  }
  if (c.count() <= 2 || TouchOnly(s2, proj.orientation, t2, t_orientation)) {
    c.WriteExtremes(out);
    return;
  }
  // Counterclockwise about +axis k is counterclockwise about normal_a when S's projected
  // orientation is positive.
  WritePolygon(c, i, j, proj.orientation < 0, out);
}

// --- Degenerate triangles -------------------------------------------------------------------

// The closed segment [p, q] (p != q) against the non-degenerate triangle t.
void SegmentTriangle(const Vector3d& p, const Vector3d& q, const TrianglePoints& t,
                     ContactGeometry& out) {
  const PlaneSide plane(t.a, t.b, t.c);
  if (plane.Side(p) != 0 || plane.Side(q) != 0) {
    out.points[0] = EdgePlaneCrossing(p, q, PlaneValue(t.a, t.b, t.c));
    out.num_points = 1;
    return;
  }
  // In t's plane: the part of [p, q] in t, whose ends are p or q, a vertex of t on [p, q], or a
  // proper crossing with an edge of t.
  const Projection proj = ChooseProjection(t.a, t.b, t.c);
  const int i = proj.i, j = proj.j;
  const std::array<const Vector3d*, 3> tv = {&t.a, &t.b, &t.c};
  const std::array<P2, 3> t2 = {Project(t.a, i, j), Project(t.b, i, j), Project(t.c, i, j)};
  const P2 p2 = Project(p, i, j), q2 = Project(q, i, j);
  Candidates c;
  if (PointInTriangle2d(p2, t2[0], t2[1], t2[2], proj.orientation)) c.AddVertex(p);
  if (PointInTriangle2d(q2, t2[0], t2[1], t2[2], proj.orientation)) c.AddVertex(q);
  for (int k = 0; k < 3; ++k) {
    if (Orient(p2, q2, t2[k]) == 0 && WithinBox2(p2, q2, t2[k])) c.AddVertex(*tv[k]);
    if (ProperCrossing2d(p2, q2, t2[k], t2[(k + 1) % 3])) {
      c.Add(EdgeLineCrossing(p, q, *tv[k], *tv[(k + 1) % 3], i, j));
    }
  }
  c.WriteExtremes(out);
}

// The closed segments [p, q] and [r, s] (p != q, r != s), known to meet.
void SegmentSegment(const Vector3d& p, const Vector3d& q, const Vector3d& r, const Vector3d& s,
                    ContactGeometry& out) {
  if (Collinear3d(p, q, r) && Collinear3d(p, q, s)) {
    // One line: the overlap runs between the middle two of the four points along an axis on
    // which p and q differ (the line is not perpendicular to it).
    int k = 0;
    while (k < 2 && p[k] == q[k]) ++k;
    std::array<const Vector3d*, 4> v = {&p, &q, &r, &s};
    std::sort(v.begin(), v.end(),
              [k](const Vector3d* x, const Vector3d* y) { return (*x)[k] < (*y)[k]; });
    out.points[0] = *v[1];
    out.num_points = 1;
    if ((*v[1])[k] != (*v[2])[k]) {
      out.points[1] = *v[2];
      out.num_points = 2;
    }
    return;
  }
  // Otherwise one point: an end on the other segment, or a proper crossing.
  for (const auto& [x, a, b] : {std::tuple{&p, &r, &s}, std::tuple{&q, &r, &s},
                                std::tuple{&r, &p, &q}, std::tuple{&s, &p, &q}}) {
    if (PointOnSegment3d(*x, *a, *b)) {
      out.points[0] = *x;
      out.num_points = 1;
      return;
    }
  }
  const std::array<std::array<const Vector3d*, 3>, 4> triples = {
      {{&p, &q, &r}, {&p, &q, &s}, {&p, &r, &s}, {&q, &r, &s}}};
  for (const auto& tri : triples) {
    if (Collinear3d(*tri[0], *tri[1], *tri[2])) continue;
    const Projection proj = ChooseProjection(*tri[0], *tri[1], *tri[2]);
    out.points[0] = EdgeLineCrossing(p, q, r, s, proj.i, proj.j);
    out.num_points = 1;
    return;
  }
}

void Degenerate(const TrianglePoints& s, const Shape& shape_s, const TrianglePoints& t,
                const Shape& shape_t, ContactGeometry& out) {
  if (shape_s.kind == Shape::kPoint || shape_t.kind == Shape::kPoint) {
    out.points[0] = shape_s.kind == Shape::kPoint ? shape_s.p : shape_t.p;
    out.num_points = 1;
    return;
  }
  if (shape_s.kind == Shape::kSegment && shape_t.kind == Shape::kSegment) {
    SegmentSegment(shape_s.p, shape_s.q, shape_t.p, shape_t.q, out);
  } else if (shape_s.kind == Shape::kSegment) {
    SegmentTriangle(shape_s.p, shape_s.q, t, out);
  } else {
    SegmentTriangle(shape_t.p, shape_t.q, s, out);
  }
}

}  // namespace

ContactGeometry TriangleContactGeometry(const TrianglePoints& s, const TrianglePoints& t) {
  ContactGeometry out;
  out.normal_a = UnitNormal(s);
  out.normal_b = UnitNormal(t);
  const bool s_degenerate = out.normal_a == Vector3d::Zero();
  const bool t_degenerate = out.normal_b == Vector3d::Zero();
  if (s_degenerate || t_degenerate) {
    Degenerate(s, Classify(s), t, Classify(t), out);
    return out;
  }
  const PlaneSide plane_t(t.a, t.b, t.c);
  const std::array<int, 3> sigma = {plane_t.Side(s.a), plane_t.Side(s.b), plane_t.Side(s.c)};
  if (sigma[0] == 0 && sigma[1] == 0 && sigma[2] == 0) {
    Coplanar(s, t, out);
    return out;
  }
  const PlaneSide plane_s(s.a, s.b, s.c);
  const std::array<int, 3> tau = {plane_s.Side(t.a), plane_s.Side(t.b), plane_s.Side(t.c)};
  GeneralPosition(s, t, sigma, tau, out);
  return out;
}

}  // namespace far
