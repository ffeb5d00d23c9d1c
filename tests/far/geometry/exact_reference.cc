#include "exact_reference.h"

#include <algorithm>
#include <array>
#include <optional>
#include <vector>

namespace far::reference {
namespace {

using QTri = std::array<QVec, 3>;

QVec operator-(const QVec& a, const QVec& b) { return QVec{a.x - b.x, a.y - b.y, a.z - b.z}; }
QVec operator+(const QVec& a, const QVec& b) { return QVec{a.x + b.x, a.y + b.y, a.z + b.z}; }
QVec operator*(const mpq_class& k, const QVec& a) { return QVec{k * a.x, k * a.y, k * a.z}; }

mpq_class Dot(const QVec& a, const QVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

QVec Cross(const QVec& a, const QVec& b) {
  return QVec{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

bool IsZero(const QVec& a) { return sgn(a.x) == 0 && sgn(a.y) == 0 && sgn(a.z) == 0; }

bool InUnitInterval(const mpq_class& x) { return sgn(x) >= 0 && x <= 1; }

QTri ToQTri(const TrianglePoints& t) { return QTri{ToQ(t.a), ToQ(t.b), ToQ(t.c)}; }

// Closed segment [a, b] (a == b allowed) contains p.
bool PointOnSegment(const QVec& p, const QVec& a, const QVec& b) {
  const QVec d = b - a;
  const QVec w = p - a;
  if (IsZero(d)) return IsZero(w);
  if (!IsZero(Cross(w, d))) return false;
  const mpq_class t = Dot(w, d);
  return sgn(t) >= 0 && t <= Dot(d, d);
}

// Closed segments [a, b] and [c, d] (either may be a point) share a point: solve
// a + lambda (b - a) = c + mu (d - c) exactly.
bool SegmentsMeet(const QVec& a, const QVec& b, const QVec& c, const QVec& d) {
  const QVec d1 = b - a;
  const QVec d2 = d - c;
  const QVec r = c - a;
  const QVec n = Cross(d1, d2);
  if (!IsZero(n)) {
    if (sgn(Dot(r, n)) != 0) return false;  // skew lines
    const mpq_class nn = Dot(n, n);
    const mpq_class lambda = Dot(Cross(r, d2), n) / nn;
    const mpq_class mu = Dot(Cross(r, d1), n) / nn;
    return InUnitInterval(lambda) && InUnitInterval(mu);
  }
  if (IsZero(d1)) return PointOnSegment(a, c, d);
  if (IsZero(d2)) return PointOnSegment(c, a, b);
  // Parallel, both proper: they meet iff collinear and their parameter intervals overlap.
  if (!IsZero(Cross(r, d1))) return false;
  const mpq_class dd = Dot(d1, d1);
  const mpq_class lc = Dot(r, d1) / dd;
  const mpq_class ld = Dot(d - a, d1) / dd;
  const mpq_class lo = std::max(mpq_class(0), mpq_class(std::min(lc, ld)));
  const mpq_class hi = std::min(mpq_class(1), mpq_class(std::max(lc, ld)));
  return lo <= hi;
}

// The two points of a degenerate (collinear) triangle that span its hull.
std::pair<QVec, QVec> HullSegment(const QTri& q) {
  int best_i = 0;
  int best_j = 1;
  mpq_class best = -1;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const QVec d = q[j] - q[i];
    const mpq_class len2 = Dot(d, d);
    if (len2 > best) {
      best = len2;
      best_i = i;
      best_j = j;
    }
  }
  return {q[best_i], q[best_j]};
}

// X in the plane of the non-degenerate triangle q with normal n lies in the closed triangle.
bool InsideTriangle(const QVec& x, const QTri& q, const QVec& n) {
  for (int i = 0; i < 3; ++i) {
    if (sgn(Dot(Cross(q[(i + 1) % 3] - q[i], x - q[i]), n)) < 0) return false;
  }
  return true;
}

// Closed segment [a, b] (a == b allowed) meets the convex hull of q (any triangle).
bool SegmentMeetsTriangle(const QVec& a, const QVec& b, const QTri& q) {
  const QVec n = Cross(q[1] - q[0], q[2] - q[0]);
  if (IsZero(n)) {
    const auto [u, v] = HullSegment(q);
    return SegmentsMeet(a, b, u, v);
  }
  const mpq_class ha = Dot(n, a - q[0]);
  const mpq_class hb = Dot(n, b - q[0]);
  if ((sgn(ha) > 0 && sgn(hb) > 0) || (sgn(ha) < 0 && sgn(hb) < 0)) return false;
  if (sgn(ha) != 0 || sgn(hb) != 0) {
    // One crossing point, constructed exactly.
    const mpq_class lambda = ha / (ha - hb);
    return InsideTriangle(a + lambda * (b - a), q, n);
  }
  // The segment lies in the plane: clip its parameter interval by the three inner half-planes
  // (n x edge points inwards).
  mpq_class lo = 0;
  mpq_class hi = 1;
  for (int i = 0; i < 3; ++i) {
    const QVec m = Cross(n, q[(i + 1) % 3] - q[i]);
    const mpq_class alpha = Dot(m, a - q[i]);
    const mpq_class beta = Dot(m, b - a);
    if (sgn(beta) == 0) {
      if (sgn(alpha) < 0) return false;
    } else {
      const mpq_class bound = -alpha / beta;
      if (sgn(beta) > 0) {
        lo = std::max(lo, bound);
      } else {
        hi = std::min(hi, bound);
      }
    }
  }
  return lo <= hi;
}

mpq_class PointSegmentSquared(const QVec& p, const QVec& a, const QVec& b) {
  const QVec d = b - a;
  const QVec w = p - a;
  const mpq_class dd = Dot(d, d);
  if (sgn(dd) == 0) return Dot(w, w);
  mpq_class t = Dot(w, d) / dd;
  if (sgn(t) < 0) t = 0;
  if (t > 1) t = 1;
  const QVec r = w - t * d;
  return Dot(r, r);
}

// Squared distance of the supporting lines if their closest points lie in both segments.
std::optional<mpq_class> SegmentInteriorSquared(const QVec& a, const QVec& b, const QVec& c,
                                                const QVec& d) {
  const QVec d1 = b - a;
  const QVec d2 = d - c;
  const QVec n = Cross(d1, d2);
  if (IsZero(n)) return std::nullopt;
  const QVec r = c - a;
  const mpq_class nn = Dot(n, n);
  const mpq_class lambda = Dot(Cross(r, d2), n) / nn;
  const mpq_class mu = Dot(Cross(r, d1), n) / nn;
  if (!InUnitInterval(lambda) || !InUnitInterval(mu)) return std::nullopt;
  const mpq_class h = Dot(r, n);
  return h * h / nn;
}

// Squared distance of p to the plane of q if p projects into the closed triangle q.
std::optional<mpq_class> VertexFaceSquared(const QVec& p, const QTri& q) {
  const QVec n = Cross(q[1] - q[0], q[2] - q[0]);
  if (IsZero(n)) return std::nullopt;
  // (e x (p - q_i)) . n depends only on the in-plane part of p - q_i.
  if (!InsideTriangle(p, q, n)) return std::nullopt;
  const mpq_class h = Dot(n, p - q[0]);
  return h * h / Dot(n, n);
}

// The part of the closed segment [a, b] in the convex hull of q, as its ends (none, one or two
// points), constructed exactly.
std::vector<QVec> ClipSegment(const QVec& a, const QVec& b, const QTri& q) {
  const QVec d = b - a;
  const QVec n = Cross(q[1] - q[0], q[2] - q[0]);
  mpq_class lo = 0;
  mpq_class hi = 1;
  if (IsZero(n)) {
    // q is the segment [u, v] (or a point): intersect the two segments.
    const auto [u, v] = HullSegment(q);
    const QVec e = v - u;
    if (IsZero(d)) return PointOnSegment(a, u, v) ? std::vector<QVec>{a} : std::vector<QVec>{};
    if (IsZero(e)) return PointOnSegment(u, a, b) ? std::vector<QVec>{u} : std::vector<QVec>{};
    const QVec cross = Cross(d, e);
    if (!IsZero(cross)) {
      if (sgn(Dot(u - a, cross)) != 0) return {};
      const mpq_class cc = Dot(cross, cross);
      const mpq_class lambda = Dot(Cross(u - a, e), cross) / cc;
      const mpq_class mu = Dot(Cross(u - a, d), cross) / cc;
      if (!InUnitInterval(lambda) || !InUnitInterval(mu)) return {};
      return {a + lambda * d};
    }
    if (!IsZero(Cross(u - a, d))) return {};  // parallel lines
    const mpq_class dd = Dot(d, d);
    const mpq_class lu = Dot(u - a, d) / dd;
    const mpq_class lv = Dot(v - a, d) / dd;
    lo = std::max(lo, mpq_class(std::min(lu, lv)));
    hi = std::min(hi, mpq_class(std::max(lu, lv)));
  } else {
    const mpq_class ha = Dot(n, a - q[0]);
    const mpq_class hb = Dot(n, b - q[0]);
    if ((sgn(ha) > 0 && sgn(hb) > 0) || (sgn(ha) < 0 && sgn(hb) < 0)) return {};
    if (sgn(ha) != 0 || sgn(hb) != 0) {
      const QVec x = a + mpq_class(ha / (ha - hb)) * d;
      return InsideTriangle(x, q, n) ? std::vector<QVec>{x} : std::vector<QVec>{};
    }
    for (int i = 0; i < 3; ++i) {
      const QVec m = Cross(n, q[(i + 1) % 3] - q[i]);
      const mpq_class alpha = Dot(m, a - q[i]);
      const mpq_class beta = Dot(m, d);
      if (sgn(beta) == 0) {
        if (sgn(alpha) < 0) return {};
      } else if (sgn(beta) > 0) {
        lo = std::max(lo, mpq_class(-alpha / beta));
      } else {
        hi = std::min(hi, mpq_class(-alpha / beta));
      }
    }
  }
  if (lo > hi) return {};
  if (lo == hi) return {a + lo * d};
  return {a + lo * d, a + hi * d};
}

bool Equal(const QVec& a, const QVec& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// The extreme points of the convex hull of distinct points.
std::vector<QVec> HullVertices(const std::vector<QVec>& p) {
  if (p.size() <= 1) return p;
  const QVec d = p[1] - p[0];
  size_t off_line = 0;
  for (size_t k = 2; k < p.size() && off_line == 0; ++k) {
    if (!IsZero(Cross(p[k] - p[0], d))) off_line = k;
  }
  if (off_line == 0) {  // collinear: the two extremes along d
    size_t lo = 0, hi = 0;
    for (size_t k = 1; k < p.size(); ++k) {
      if (Dot(p[k] - p[0], d) < Dot(p[lo] - p[0], d)) lo = k;
      if (Dot(p[k] - p[0], d) > Dot(p[hi] - p[0], d)) hi = k;
    }
    return {p[lo], p[hi]};
  }
  // Coplanar: gift wrapping about the normal, collinear points dropped.
  const QVec normal = Cross(d, p[off_line] - p[0]);
  size_t start = 0;
  for (size_t k = 1; k < p.size(); ++k) {
    if (p[k].x < p[start].x ||
        (p[k].x == p[start].x &&
         (p[k].y < p[start].y || (p[k].y == p[start].y && p[k].z < p[start].z)))) {
      start = k;
    }
  }
  // The lexicographically smallest point is extreme (a linear functional's unique minimum).
  std::vector<QVec> hull;
  size_t current = start;
  do {
    hull.push_back(p[current]);
    size_t next = current == 0 ? 1 : 0;
    for (size_t k = 0; k < p.size(); ++k) {
      if (k == current) continue;
      const int side = sgn(Dot(Cross(p[next] - p[current], p[k] - p[current]), normal));
      const bool farther = side == 0 && Dot(p[k] - p[current], p[k] - p[current]) >
                                            Dot(p[next] - p[current], p[next] - p[current]);
      if (side < 0 || farther) next = k;
    }
    current = next;
  } while (current != start && hull.size() <= p.size());
  return hull;
}

}  // namespace

QVec ToQ(const Eigen::Vector3d& p) {
  return QVec{mpq_class(p.x()), mpq_class(p.y()), mpq_class(p.z())};
}

int ExactOrient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
  const QVec qa = ToQ(a);
  return sgn(Dot(Cross(ToQ(b) - qa, ToQ(c) - qa), ToQ(d) - qa));
}

int ExactOrient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const mpq_class ux = mpq_class(bx) - mpq_class(ax);
  const mpq_class uy = mpq_class(by) - mpq_class(ay);
  const mpq_class vx = mpq_class(cx) - mpq_class(ax);
  const mpq_class vy = mpq_class(cy) - mpq_class(ay);
  return sgn(ux * vy - uy * vx);
}

bool ExactTrianglesIntersect(const TrianglePoints& s, const TrianglePoints& t) {
  // Two closed convex sets of dimension <= 2 in space meet iff an edge of one meets the other:
  // the intersection (a convex set on the line where the planes meet, or a convex polygon when
  // coplanar) has a point on the boundary of s or of t, and that boundary is the edges. A
  // degenerate triangle is the union of its edges, and SegmentMeetsTriangle handles a
  // degenerate hull.
  const QTri qs = ToQTri(s);
  const QTri qt = ToQTri(t);
  for (int i = 0; i < 3; ++i) {
    if (SegmentMeetsTriangle(qs[i], qs[(i + 1) % 3], qt)) return true;
    if (SegmentMeetsTriangle(qt[i], qt[(i + 1) % 3], qs)) return true;
  }
  return false;
}

mpq_class ExactSquaredDistance(const TrianglePoints& s, const TrianglePoints& t) {
  if (ExactTrianglesIntersect(s, t)) return 0;
  // Disjoint: the minimum over vertex-edge, edge-edge interior and vertex-face candidates.
  const QTri qs = ToQTri(s);
  const QTri qt = ToQTri(t);
  mpq_class best = PointSegmentSquared(qs[0], qt[0], qt[1]);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      best = std::min(best, PointSegmentSquared(qs[i], qt[j], qt[(j + 1) % 3]));
      best = std::min(best, PointSegmentSquared(qt[i], qs[j], qs[(j + 1) % 3]));
      if (const auto v = SegmentInteriorSquared(qs[i], qs[(i + 1) % 3], qt[j], qt[(j + 1) % 3])) {
        best = std::min(best, *v);
      }
    }
    if (const auto v = VertexFaceSquared(qs[i], qt)) best = std::min(best, *v);
    if (const auto v = VertexFaceSquared(qt[i], qs)) best = std::min(best, *v);
  }
  return best;
}

}  // namespace far::reference

namespace far::reference {

std::vector<QVec> ExactIntersectionExtremes(const TrianglePoints& s, const TrianglePoints& t) {
  const QTri qs = ToQTri(s);
  const QTri qt = ToQTri(t);
  std::vector<QVec> candidates;
  const auto add = [&](const QVec& x) {
    for (const QVec& y : candidates) {
      if (Equal(x, y)) return;
    }
    candidates.push_back(x);
  };
  for (const auto& [mine, other] : {std::pair{&qs, &qt}, std::pair{&qt, &qs}}) {
    for (int i = 0; i < 3; ++i) {
      for (const QVec& x : ClipSegment((*mine)[i], (*mine)[(i + 1) % 3], *other)) add(x);
    }
  }
  return HullVertices(candidates);
}

}  // namespace far::reference
