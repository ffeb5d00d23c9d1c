#pragma once

// The exact building blocks that the intersection test (triangle_intersection.cc) and the
// contact geometry (triangle_contact.cc) share: projections onto coordinate planes chosen
// exactly, what a degenerate triangle is, point-in-shape tests and Guigue and Devillers' apex.
// Every decision is an exact predicate (predicates.h) or a comparison of input coordinates.

#include <algorithm>
#include <array>

#include <Eigen/Geometry>

#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_tests.h"

namespace far::internal {

using Eigen::Vector3d;

// A point projected onto a coordinate plane (exact: coordinates are only selected).
struct P2 {
  double x, y;
};

inline P2 Project(const Vector3d& p, int i, int j) { return P2{p[i], p[j]}; }

inline int Orient(const P2& a, const P2& b, const P2& c) {
  return Orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

// Returns true iff p, known to be collinear with a and b, lies on the closed segment [a, b]
// (also right when a == b: then p must equal a).
inline bool WithinBox2(const P2& a, const P2& b, const P2& p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

inline bool WithinBox3(const Vector3d& a, const Vector3d& b, const Vector3d& p) {
  for (int k = 0; k < 3; ++k) {
    if (p[k] < std::min(a[k], b[k]) || p[k] > std::max(a[k], b[k])) return false;
  }
  return true;
}

// Closed non-degenerate triangle (a, b, c) with orientation `orientation` (+1 or -1) contains p.
inline bool PointInTriangle2d(const P2& p, const P2& a, const P2& b, const P2& c, int orientation) {
  return Orient(a, b, p) * orientation >= 0 && Orient(b, c, p) * orientation >= 0 &&
         Orient(c, a, p) * orientation >= 0;
}

// Chooses the coordinate plane to project a non-degenerate triangle (a, b, c) onto: drops the
// axis k along which its normal has a nonzero component (decided exactly), so that the
// projection is one-to-one on the triangle's plane. Returns the kept axes (i, j) and the
// projected orientation (+1 or -1).
struct Projection {
  int i, j;
  int orientation;
};

inline Projection ChooseProjection(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  // Prefer dropping the axis with the largest floating-point normal component (the best
  // conditioned projection); any axis with a nonzero exact component would be correct.
  const Vector3d n = (b - a).cross(c - a);
  int k = 0;
  if (std::abs(n.y()) > std::abs(n[k])) k = 1;
  if (std::abs(n.z()) > std::abs(n[k])) k = 2;
  for (int attempt = 0; attempt < 3; ++attempt, k = (k + 1) % 3) {
    const int i = (k + 1) % 3;
    const int j = (k + 2) % 3;
    const int orientation = Orient2dProjected(a, b, c, i, j);
    if (orientation != 0) return Projection{i, j, orientation};
  }
  return Projection{0, 1, 0};  // degenerate triangle: callers never pass one
}

// --- Degenerate triangles: what they are -----------------------------------------------------

struct Shape {
  enum Kind { kTriangle, kSegment, kPoint } kind;
  Vector3d p, q;  // kSegment: the end points; kPoint: p
};

inline Shape Classify(const TrianglePoints& s) {
  if (!Collinear3d(s.a, s.b, s.c)) return Shape{Shape::kTriangle, {}, {}};
  // Collinear: the hull is the segment between the extreme points along any axis on which the
  // points are not all equal (exact comparisons).
  const std::array<const Vector3d*, 3> v = {&s.a, &s.b, &s.c};
  for (int k = 0; k < 3; ++k) {
    const auto [lo, hi] = std::minmax_element(
        v.begin(), v.end(),
        [k](const Vector3d* x, const Vector3d* y) { return (*x)[k] < (*y)[k]; });
    if ((**lo)[k] < (**hi)[k]) return Shape{Shape::kSegment, **lo, **hi};
  }
  return Shape{Shape::kPoint, s.a, s.a};
}

inline bool PointOnSegment3d(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  return Collinear3d(a, b, p) && WithinBox3(a, b, p);
}

inline bool PointTriangle3d(const Vector3d& p, const TrianglePoints& t) {
  if (Orient3d(t.a, t.b, t.c, p) != 0) return false;
  const Projection proj = ChooseProjection(t.a, t.b, t.c);
  return PointInTriangle2d(Project(p, proj.i, proj.j), Project(t.a, proj.i, proj.j),
                           Project(t.b, proj.i, proj.j), Project(t.c, proj.i, proj.j),
                           proj.orientation);
}

// Picks the apex of a triangle from the signs of its vertices w.r.t. the other plane: a vertex
// whose two neighbours are strictly on one side of its level. Returns its index and eps (+1 if
// the others are below it, -1 if above). @pre the signs are not all equal.
struct Apex {
  int index;
  int eps;
};

inline Apex FindApex(const std::array<int, 3>& sign) {
  // A vertex whose strict sign no other vertex shares: the others are on its opposite closed
  // side, and strictly below or above its level.
  for (int i = 0; i < 3; ++i) {
    if (sign[i] != 0 && sign[(i + 1) % 3] != sign[i] && sign[(i + 2) % 3] != sign[i]) {
      return Apex{i, sign[i]};
    }
  }
  // Otherwise the pattern is (0, s, s) up to rotation: the vertex on the plane is the apex.
  for (int i = 0; i < 3; ++i) {
    if (sign[i] == 0) return Apex{i, -sign[(i + 1) % 3]};
  }
  return Apex{0, 0};  // unreachable for valid input
}

// Guigue and Devillers' labelling of a pair in general position (triangle_intersection.cc
// derives it): each triangle's apex (v of s, u of t) and its other two corners, ordered so that
// both apexes have eps = +1. Then s cuts [i2, i1] and t cuts [k1, k2] from the line where the
// planes meet, i1 on edge (v, w1), i2 on (v, w2), k1 on (u, z1), k2 on (u, z2).
struct ApexLabels {
  const Vector3d* v;
  const Vector3d* w1;
  const Vector3d* w2;
  const Vector3d* u;
  const Vector3d* z1;
  const Vector3d* z2;
  int apex_s, apex_t;  // the apexes' indices in s and t
};

// @pre sigma (s's corners against t's plane) and tau (t's against s's) are not all equal.
inline ApexLabels LabelApexes(const TrianglePoints& s, const TrianglePoints& t,
                              const std::array<int, 3>& sigma, const std::array<int, 3>& tau) {
  const std::array<const Vector3d*, 3> sv = {&s.a, &s.b, &s.c};
  const std::array<const Vector3d*, 3> tv = {&t.a, &t.b, &t.c};
  const Apex apex_s = FindApex(sigma);
  const Apex apex_t = FindApex(tau);
  ApexLabels labels{sv[apex_s.index],
                    sv[(apex_s.index + 1) % 3],
                    sv[(apex_s.index + 2) % 3],
                    tv[apex_t.index],
                    tv[(apex_t.index + 1) % 3],
                    tv[(apex_t.index + 2) % 3],
                    apex_s.index,
                    apex_t.index};
  if (apex_t.eps < 0) std::swap(labels.w1, labels.w2);
  if (apex_s.eps < 0) std::swap(labels.z1, labels.z2);
  return labels;
}

}  // namespace far::internal
