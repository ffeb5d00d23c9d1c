// Triangle-triangle distance in double, and the conservative predicate "distance <= D".
//
// Method. Intersecting triangles (exact test, triangle_intersection.cc) are at distance 0.
// For disjoint closed triangles (degenerate ones included) the distance is attained by a pair
// of features whose dimensions sum to at most 2, so it is the minimum of
//   - 18 vertex-edge distances (each vertex of one triangle to each edge of the other),
//   - 9 edge-edge candidates: a point pair near the closest points of the supporting lines,
//   - 6 vertex-face candidates: the distance of a vertex to the other triangle's plane, used
//     only when the vertex certainly projects into the triangle.
// Parallel edges and degenerate triangles need no special case: their exact cross products are
// zero, those candidates are skipped, and the vertex-edge candidates are then optimal.
//
// Robustness. Every vector is a difference of two input points computed directly (never via a
// translated copy), so its rounding error is relative to its own length. Plane and line
// normals come from internal::RoundedCross, whose components are within 2^-52 relative of
// the exact cross product's (exact expansions, or Kahan's determinant with a fused
// multiply-add where the differences are exact), so their directions are accurate to a few
// ulps even for slivers (aspect 1e8) and nearly parallel edges. Every vertex-edge and edge-edge
// candidate is the length of a vector between two actual points of the two segments (parameters
// clamped to [0, 1]), so it never underestimates by more than its evaluation error, whatever the
// conditioning.
//   - Edge-edge: s is where line 1 crosses the plane through line 2 spanned by the common
//     normal n (a lateral formula, well conditioned in the numerator), t is the best t for
//     that s. For nearly parallel edges s may be far off, but (s, t(s)) stays in the "valley"
//     of the distance function, whose height above the optimum is the lateral offset
//     |s - s*| |e1| sin(angle) <= 69 eps L; where t(s) leaves [0, 1] the valley meets an end
//     point of segment 2 first, and that vertex-edge candidate is as good.
//   - Vertex-face: accepted only when all three lateral distances (unit in-plane edge normal .
//     (p - q_i)) are >= kFaceMargin eps L, more than their rounding error (<= 23 eps L), so an
//     accepted foot is truly inside. A rejected foot that is truly inside lies within 55 eps L
//     of an edge line, hence of the boundary (for an interior point of a convex polygon the
//     distance to the boundary is the smallest distance to an edge line), and the vertex-edge
//     candidate to that edge is within 55 eps L + 13 eps L of the plane distance.
//
// Error bound (first order in eps = 2^-53, hand-derived; constants rounded up to cover the
// second-order terms). Let L be the diagonal of the bounding box of the six vertices and d the
// exact distance of the closed triangles given by the double input. Then
//   TriangleDistance(s, t) = d~  with  d - 32 eps L <= d~ <= d + 128 eps L
// (underestimate: evaluation only, <= 13 eps L; overestimate: <= 92 eps L from the edge-edge
// valley argument or 68 eps L from a rejected face foot, including evaluation).
// TrianglesWithinDistance(s, t, D) returns d~ <= D + kSlack eps L with kSlack = 256, twice the
// overestimate bound: it NEVER misses a pair with d <= D, and it may include pairs with
// d <= D + 288 eps L (for L = 1 that is 3.2e-14; for a pair 1e6 across, 3.2e-8).
// Intersecting pairs are found by the exact test and are always within.
// Before the exact work the predicate rejects pairs that a cheap lower bound already shows
// farther than the limit: the largest box gap, and the gap along each triangle's normal, the
// line between the centroids and the edge cross products (GapExceeds below, which proves
// distance > limit > D for every pair it rejects).
// For the bound to hold the arithmetic must not overflow or underflow: the input range of the
// predicates (far/internal/predicates.h) suffices. Tests check "never misses" and the two-sided
// bound against exact rational distances on random and hard cases
// (tests/far/geometry/triangle_distance_test.cc); the largest errors seen there are below
// 2 eps L, far inside the bound.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Geometry>

#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_contact.h"
#include "far/geometry/triangle_tests.h"

namespace far {
namespace {

using Eigen::Vector3d;

constexpr double kEps = 0x1p-53;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kFaceMargin = 32.0;  // a face foot is accepted this far inside, in eps * L
constexpr double kSlack = 256.0;      // predicate slack, in eps * L (2x the overestimate bound)

// The bounding boxes of the two triangles, from which both the pair's scale L and the box gap
// are read (computed once per pair).
struct PairBoxes {
  explicit PairBoxes(const TrianglePoints& s, const TrianglePoints& t)
      : s_min(s.a.array().min(s.b.array()).min(s.c.array())),
        s_max(s.a.array().max(s.b.array()).max(s.c.array())),
        t_min(t.a.array().min(t.b.array()).min(t.c.array())),
        t_max(t.a.array().max(t.b.array()).max(t.c.array())) {}
  // L: the diagonal of the bounding box of the six vertices.
  double Scale() const { return (s_max.max(t_max) - s_min.min(t_min)).matrix().norm(); }
  // The largest gap between the two boxes along a coordinate axis (<= 0 if they overlap): a
  // lower bound of the distance.
  double Gap() const { return (t_min - s_max).max(s_min - t_max).maxCoeff(); }
  Eigen::Array3d s_min, s_max, t_min, t_max;
};

// Returns n / |n| without overflow or underflow in the norm. @pre n != 0.
inline Vector3d Normalized(const Vector3d& n) {
  const Vector3d scaled = n / n.cwiseAbs().maxCoeff();
  return scaled / scaled.norm();
}

// Squared distance from p to the closed segment [a, b] (a == b allowed). Squared, so that the
// 18 vertex-edge candidates take one square root: sqrt is correctly rounded and monotone, so
// the root of their smallest square is the smallest of their norms, bit for bit. `foot`, when
// given, receives the closest point of the segment.
double PointSegmentSquaredDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                   Vector3d* foot = nullptr) {
  const Vector3d e = b - a;
  const Vector3d w = p - a;
  const double ee = e.squaredNorm();
  double t = 0.0;
  if (ee > 0.0) t = std::clamp(w.dot(e) / ee, 0.0, 1.0);
  if (foot != nullptr) *foot = a + t * e;
  return (w - t * e).squaredNorm();
}

// Where the smallest candidate so far was attained: points on the first and second triangle.
struct Witness {
  Vector3d on_s, on_t;
};

// The length of a vector between two points of [a, b] and [c, d] near the closest points of
// their supporting lines (see the valley argument above), or +inf for parallel segments.
double EdgeEdgeDistance(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d,
                        Witness* witness = nullptr) {
  const Vector3d cross = internal::RoundedCross(a, b, c, d);
  // Parallel (or a zero-length edge): a vertex-edge candidate is optimal.
  if (cross.x() == 0.0 && cross.y() == 0.0 && cross.z() == 0.0) return kInf;
  const Vector3d n = Normalized(cross);
  const Vector3d e1 = b - a;
  const Vector3d e2 = d - c;
  // s: where line 1 crosses the plane through line 2 with normal m2 = e2 x n (unit).
  const Vector3d m2 = Normalized(e2.cross(n));
  const double denominator = m2.dot(e1);
  double s = 0.0;
  if (denominator != 0.0) s = std::clamp(m2.dot(c - a) / denominator, 0.0, 1.0);
  // t: the best t for that s, clamped; then the actual distance of the two points.
  const Vector3d r = (a - c) + s * e1;
  const double t = std::clamp(r.dot(e2) / e2.squaredNorm(), 0.0, 1.0);
  if (witness != nullptr) *witness = Witness{a + s * e1, c + t * e2};
  return (r - t * e2).norm();
}

// A triangle's unit normal and inward unit edge normals, when it is not degenerate.
struct FaceFrame {
  bool valid = false;
  Vector3d normal;
  std::array<Vector3d, 3> inward;
};

FaceFrame MakeFaceFrame(const std::array<const Vector3d*, 3>& v) {
  FaceFrame frame;
  const Vector3d cross = internal::RoundedCross(*v[0], *v[1], *v[0], *v[2]);
  if (cross.x() == 0.0 && cross.y() == 0.0 && cross.z() == 0.0) return frame;  // collinear
  frame.valid = true;
  frame.normal = Normalized(cross);
  for (int i = 0; i < 3; ++i) {
    // n x (edge direction) points into the triangle for the orientation that n comes from.
    frame.inward[i] = Normalized(frame.normal.cross(*v[(i + 1) % 3] - *v[i]));
  }
  return frame;
}

// The distance from p to the plane of the triangle if p projects at least `margin` inside it,
// else +inf. `foot`, when given, receives p's projection onto the plane.
double VertexFaceDistance(const Vector3d& p, const std::array<const Vector3d*, 3>& v,
                          const FaceFrame& frame, double margin, Vector3d* foot = nullptr) {
  for (int i = 0; i < 3; ++i) {
    if (frame.inward[i].dot(p - *v[i]) < margin) return kInf;
  }
  const double height = frame.normal.dot(p - *v[0]);
  if (foot != nullptr) *foot = p - height * frame.normal;
  return std::abs(height);
}

// The distance of two triangles known to be disjoint, and where it is attained when `witness`
// is given (the points of the smallest candidate; the value is the same either way).
double DisjointDistance(const TrianglePoints& s, const TrianglePoints& t, double scale,
                        Witness* witness = nullptr) {
  const double margin = kFaceMargin * kEps * scale;
  const std::array<const Vector3d*, 3> sv = {&s.a, &s.b, &s.c};
  const std::array<const Vector3d*, 3> tv = {&t.a, &t.b, &t.c};
  // Vertex-edge, both ways. The best pair is remembered by index (the feet are recomputed).
  double best_squared = kInf;
  int best_vertex = 0, best_edge = 0;
  bool best_on_t = true;  // the vertex is s's and the edge t's
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double to_t = PointSegmentSquaredDistance(*sv[i], *tv[j], *tv[(j + 1) % 3]);
      if (to_t < best_squared) {
        best_squared = to_t;
        best_vertex = i, best_edge = j, best_on_t = true;
      }
      const double to_s = PointSegmentSquaredDistance(*tv[i], *sv[j], *sv[(j + 1) % 3]);
      if (to_s < best_squared) {
        best_squared = to_s;
        best_vertex = i, best_edge = j, best_on_t = false;
      }
    }
  }
  if (witness != nullptr) {
    const auto& vertices = best_on_t ? sv : tv;
    const auto& edges = best_on_t ? tv : sv;
    Vector3d foot;
    PointSegmentSquaredDistance(*vertices[best_vertex], *edges[best_edge],
                                *edges[(best_edge + 1) % 3], &foot);
    *witness = best_on_t ? Witness{*sv[best_vertex], foot} : Witness{foot, *tv[best_vertex]};
  }
  double best = std::sqrt(best_squared);
  // Vertex-face, both ways.
  const FaceFrame frame_s = MakeFaceFrame(sv);
  const FaceFrame frame_t = MakeFaceFrame(tv);
  for (int i = 0; i < 3; ++i) {
    Vector3d foot;
    Vector3d* foot_out = witness != nullptr ? &foot : nullptr;
    if (frame_t.valid) {
      const double d = VertexFaceDistance(*sv[i], tv, frame_t, margin, foot_out);
      if (d < best) {
        best = d;
        if (witness != nullptr) *witness = Witness{*sv[i], foot};
      }
    }
    if (frame_s.valid) {
      const double d = VertexFaceDistance(*tv[i], sv, frame_s, margin, foot_out);
      if (d < best) {
        best = d;
        if (witness != nullptr) *witness = Witness{foot, *tv[i]};
      }
    }
  }
  // Edge-edge, last: an edge pair whose boxes are farther apart than the best candidate so far
  // cannot be smaller, and is skipped. Its candidate is a vector between points of the two
  // segments, computed within 13 eps L, and the computed box gap (one rounded difference of two
  // coordinates) is within eps L of the exact one, so a gap above best + 16 eps L means a
  // candidate above best: the minimum, hence the result, is the same bit for bit.
  const double skip_above = best + 16 * kEps * scale;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vector3d &a = *sv[i], &b = *sv[(i + 1) % 3], &c = *tv[j], &d = *tv[(j + 1) % 3];
      const Eigen::Array3d gap = (c.array().min(d.array()) - a.array().max(b.array()))
                                     .max(a.array().min(b.array()) - c.array().max(d.array()));
      if (gap.maxCoeff() > skip_above) continue;
      Witness candidate;
      const double distance =
          EdgeEdgeDistance(a, b, c, d, witness != nullptr ? &candidate : nullptr);
      if (distance < best) {
        best = distance;
        if (witness != nullptr) *witness = candidate;
      }
    }
  }
  return best;
}

// The five other vertices relative to s.a, shared by every axis tried on one pair.
struct PairOffsets {
  explicit PairOffsets(const TrianglePoints& s, const TrianglePoints& t)
      : sb(s.b - s.a), sc(s.c - s.a), ta(t.a - s.a), tb(t.b - s.a), tc(t.c - s.a) {}
  Vector3d sb, sc, ta, tb, tc;
};

// True when the gap between the projections of the two triangles onto `n` (any vector; a zero
// or non-finite one never separates) proves distance(s, t) > limit.
// For any axis n, distance >= gap / |n|. Error: each projection n . (x - o), with x - o and the
// dot product rounded, is within 4.01 eps |n| L of its exact value (Cauchy-Schwarz, |x - o| <= L
// for x and o among the six vertices), so the exact gap is >= the computed one (1 - eps) minus
// 8.02 eps |n| L; |n| computed is within 3 eps of |n|, and the product and sum below add a few
// eps. A gap accepted against limit + 64 eps L therefore gives distance > (1 - 8 eps) limit +
// 55 eps L, and limit < 1.01 L whenever a gap passes (no projection gap exceeds |n| L), so
// distance > limit: the rejected pair is farther than the limit, hence than D, and
// TrianglesWithinDistance never misses because of it. The axis itself needs no accuracy: it
// may be any rounded vector (a rounded normal, cross product or difference of centroids).
bool GapExceeds(const Vector3d& n, const PairOffsets& d, double limit, double scale) {
  const double length = n.norm();
  if (!(length > 0) || !std::isfinite(length)) return false;
  const double s1 = n.dot(d.sb), s2 = n.dot(d.sc);
  const double t0 = n.dot(d.ta), t1 = n.dot(d.tb), t2 = n.dot(d.tc);
  const double s_lo = std::min({0.0, s1, s2}), s_hi = std::max({0.0, s1, s2});
  const double t_lo = std::min({t0, t1, t2}), t_hi = std::max({t0, t1, t2});
  const double gap = std::max(t_lo - s_hi, s_lo - t_hi);
  return gap > length * (limit + 64 * kEps * scale);
}

// Separating axes that prove the pair farther than the limit, cheapest and likeliest first:
// both triangles' normals (a degenerate triangle's is zero: skipped), the line between their
// centroids, and the nine cross products of an edge of each (the axes on which two disjoint
// convex polyhedra always show a gap, with the normals). Of the pairs the normals leave that are
// beyond the limit, the others reject about nine in ten, at about a fourth of the exact
// distance's cost (paper-leaves, D = 0.001 of the scene's diagonal; bench/RESULTS.md).
bool AxesSeparate(const TrianglePoints& s, const TrianglePoints& t, double limit, double scale) {
  const PairOffsets d(s, t);
  if (GapExceeds(d.sb.cross(d.sc), d, limit, scale)) return true;
  if (GapExceeds((d.tb - d.ta).cross(d.tc - d.ta), d, limit, scale)) return true;
  if (GapExceeds(d.ta + d.tb + d.tc - d.sb - d.sc, d, limit, scale)) return true;
  const Vector3d s_edges[3] = {d.sb, d.sc - d.sb, d.sc};
  const Vector3d t_edges[3] = {d.tb - d.ta, d.tc - d.tb, d.tc - d.ta};
  for (const Vector3d& e : s_edges) {
    for (const Vector3d& f : t_edges) {
      if (GapExceeds(e.cross(f), d, limit, scale)) return true;
    }
  }
  return false;
}

}  // namespace

namespace {

// Whether t comes before s in a fixed order of triangles (their nine coordinates, compared
// lexicographically). The functions below evaluate a pair in that order, so that their answer,
// rounding included, is the same whichever triangle the caller names first: the stages meet a
// pair in the order of the objects' slots, which follow the history of a scene's updates.
bool Before(const TrianglePoints& t, const TrianglePoints& s) {
  const std::array<double, 9> x = {t.a.x(), t.a.y(), t.a.z(), t.b.x(), t.b.y(),
                                   t.b.z(), t.c.x(), t.c.y(), t.c.z()};
  const std::array<double, 9> y = {s.a.x(), s.a.y(), s.a.z(), s.b.x(), s.b.y(),
                                   s.b.z(), s.c.x(), s.c.y(), s.c.z()};
  return x < y;
}

}  // namespace

double TriangleDistance(const TrianglePoints& s, const TrianglePoints& t) {
  if (Before(t, s)) return TriangleDistance(t, s);
  if (TrianglesIntersect(s, t)) return 0.0;
  return DisjointDistance(s, t, PairBoxes(s, t).Scale());
}

std::optional<double> TriangleDistanceIfWithin(const TrianglePoints& s, const TrianglePoints& t,
                                               double max_distance) {
  if (Before(t, s)) return TriangleDistanceIfWithin(t, s, max_distance);
  const PairBoxes boxes(s, t);
  const double scale = boxes.Scale();
  const double limit = max_distance + kSlack * kEps * scale;
  // Boxes farther apart than the limit: the distance is larger (the gap is a lower bound, and
  // the slack covers its rounding; see the bound at the top of this file).
  if (boxes.Gap() > limit) return std::nullopt;
  if (AxesSeparate(s, t, limit, scale)) return std::nullopt;
  if (TrianglesIntersect(s, t)) return 0.0;
  // TriangleDistance's value: DisjointDistance at the same scale.
  const double distance = DisjointDistance(s, t, scale);
  if (distance <= limit) return distance;
  return std::nullopt;
}

ClosestPoints TriangleClosestPoints(const TrianglePoints& s, const TrianglePoints& t) {
  if (Before(t, s)) {
    const ClosestPoints swapped = TriangleClosestPoints(t, s);
    return ClosestPoints{swapped.point_b, swapped.point_a};
  }
  if (TrianglesIntersect(s, t)) {
    const Vector3d common = TriangleContactGeometry(s, t).points[0];
    return ClosestPoints{common, common};
  }
  return DisjointClosestPoints(s, t);
}

ClosestPoints DisjointClosestPoints(const TrianglePoints& s, const TrianglePoints& t) {
  if (Before(t, s)) {
    const ClosestPoints swapped = DisjointClosestPoints(t, s);
    return ClosestPoints{swapped.point_b, swapped.point_a};
  }
  Witness witness;
  DisjointDistance(s, t, PairBoxes(s, t).Scale(), &witness);
  return ClosestPoints{witness.on_s, witness.on_t};
}

bool TrianglesWithinDistance(const TrianglePoints& s, const TrianglePoints& t,
                             double max_distance) {
  return TriangleDistanceIfWithin(s, t, max_distance).has_value();
}

}  // namespace far
