#pragma once

// Shared by the offsets tests: triangle families at many scales and positions, samples of a
// triangle grown by a ball, and exact-as-possible membership tests for the offset pieces.

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "far/offsets/bounding_offset.h"

namespace far::test {

struct Triangle {
  Eigen::Vector3d a, b, c;
  std::string kind;
};

/// Returns a uniformly random unit vector.
inline Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Vector3d w;
  do {
    w = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  } while (w.norm() < 1e-3);
  return w.normalized();
}

/// Returns a uniformly random point in the ball of radius `radius`.
inline Eigen::Vector3d RandomInBall(std::mt19937_64& rng, double radius) {
  std::uniform_real_distribution<double> unit(0, 1);
  return RandomDirection(rng) * (radius * std::cbrt(unit(rng)));
}

/// Returns a random rotation.
inline Eigen::Matrix3d RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

/// Returns every family of triangle at size `scale` around `base`: fat, needle and cap
/// slivers (aspect 1e8), near- and exactly-collinear, repeated and coincident vertices, caps
/// thin enough (1e-13, 1e-16) that no normal can be trusted; each in both windings.
inline std::vector<Triangle> TriangleFamilies(std::mt19937_64& rng, double scale,
                                              const Eigen::Vector3d& base) {
  std::vector<Triangle> out;
  const auto add = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const std::string& kind) {
    out.push_back({a, b, c, kind});
    out.push_back({a, c, b, kind + "/reversed"});
  };
  const Eigen::Vector3d d = RandomDirection(rng);
  Eigen::Vector3d perp = d.cross(RandomDirection(rng)).normalized();
  const Eigen::Vector3d a = base + RandomInBall(rng, scale);
  const Eigen::Vector3d b = a + scale * d;
  add(a, base + RandomInBall(rng, scale), base + RandomInBall(rng, scale), "fat");
  add(a, b, b + 1e-8 * scale * perp, "needle");
  add(a, b, a + 0.5 * scale * d + 1e-8 * scale * perp, "cap");
  add(a, b, a + 0.5 * scale * d + 1e-13 * scale * perp, "cap1e-13");
  add(a, b, a + 0.5 * scale * d + 1e-16 * scale * perp, "cap1e-16");
  add(a, b, a + 0.3 * (b - a), "near-collinear");
  add(a, b, a + 1.7 * (b - a), "near-collinear-outside");
  const Eigen::Vector3d step(scale, 0, 0);
  add(base, base + step, base + 0.375 * step, "collinear");
  add(a, a, b, "repeated-ab");
  add(a, b, b, "repeated-bc");
  add(a, b, a, "repeated-ca");
  add(a, a, a, "coincident");
  return out;
}

/// Returns points of the triangle: its vertices, edge points and interior points.
inline std::vector<Eigen::Vector3d> TrianglePoints(std::mt19937_64& rng, const Triangle& t,
                                                   int interior) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> points = {t.a, t.b, t.c};
  const std::array<Eigen::Vector3d, 3> v = {t.a, t.b, t.c};
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& p = v[i];
    const Eigen::Vector3d& q = v[(i + 1) % 3];
    points.push_back(p + 0.5 * (q - p));
    points.push_back(p + unit(rng) * (q - p));
  }
  for (int k = 0; k < interior; ++k) {
    double s = unit(rng), w = unit(rng);
    if (s + w > 1) s = 1 - s, w = 1 - w;
    points.push_back(t.a + s * (t.b - t.a) + w * (t.c - t.a));
  }
  return points;
}

/// Returns offsets of length r (random directions, world axes and diagonals, the triangle's
/// normal both ways, in-plane directions) and random offsets of length below r.
inline std::vector<Eigen::Vector3d> BallOffsets(std::mt19937_64& rng, const Triangle& t, double r,
                                                int random) {
  std::vector<Eigen::Vector3d> offsets;
  for (int k = 0; k < random; ++k) {
    offsets.push_back(r * RandomDirection(rng));
    offsets.push_back(RandomInBall(rng, r));
  }
  for (int i = 0; i < 3; ++i) {
    offsets.push_back(r * Eigen::Vector3d::Unit(i));
    offsets.push_back(-r * Eigen::Vector3d::Unit(i));
  }
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
    offsets.push_back(r * s / std::sqrt(3.0));
  }
  // The normal in long double (a reference independent of the implementation).
  using V = Eigen::Matrix<long double, 3, 1>;
  const V n = (t.b - t.a).cast<long double>().cross((t.c - t.a).cast<long double>());
  if (n.norm() > 0) {
    const Eigen::Vector3d unit_n = (n / n.norm()).cast<double>();
    offsets.push_back(r * unit_n);
    offsets.push_back(-r * unit_n);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d w = RandomDirection(rng);
      const Eigen::Vector3d in_plane = w - w.dot(unit_n) * unit_n;
      if (in_plane.norm() > 1e-3) offsets.push_back(r * in_plane.normalized());
    }
  }
  offsets.push_back(Eigen::Vector3d::Zero());
  return offsets;
}

/// Returns whether p is in the box (no tolerance).
inline bool InsideObb(const Obb& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - box.center;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d.dot(box.axes.col(i))) > box.half_extents[i]) return false;
  }
  return true;
}

// GCC and Clang on x86-64: binary128 with a 113-bit significand (software arithmetic).
__extension__ typedef __float128 Quad;

/// Returns the sign of (q - p0) . ((p1 - p0) x (p2 - p0)): + when q is on the side the
/// triangle's normal points to. A double evaluation decides when it clears its error bound;
/// otherwise binary128 does (the differences are exact there, and the products' error is far
/// below the thinnest prism tested: a needle 1e-14 wide and 1e-20 thick at coordinates 1e-6).
inline int Orientation(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& p2, const Eigen::Vector3d& q) {
  const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0, d = q - p0;
  const double det = d.dot(e1.cross(e2));
  const Eigen::Vector3d a1 = e1.cwiseAbs(), a2 = e2.cwiseAbs();
  const Eigen::Vector3d permanent(a1.y() * a2.z() + a1.z() * a2.y(),
                                  a1.z() * a2.x() + a1.x() * a2.z(),
                                  a1.x() * a2.y() + a1.y() * a2.x());
  const double bound = 16 * 0x1p-53 * d.cwiseAbs().dot(permanent);
  if (det > bound) return 1;
  if (det < -bound) return -1;
  Quad x1[3], x2[3], y[3];
  for (int i = 0; i < 3; ++i) {
    x1[i] = static_cast<Quad>(p1[i]) - static_cast<Quad>(p0[i]);
    x2[i] = static_cast<Quad>(p2[i]) - static_cast<Quad>(p0[i]);
    y[i] = static_cast<Quad>(q[i]) - static_cast<Quad>(p0[i]);
  }
  const Quad exact = y[0] * (x1[1] * x2[2] - x1[2] * x2[1]) +
                     y[1] * (x1[2] * x2[0] - x1[0] * x2[2]) +
                     y[2] * (x1[0] * x2[1] - x1[1] * x2[0]);
  return exact > 0 ? 1 : (exact < 0 ? -1 : 0);
}

/// Returns whether p is on the inner side of (or on) every face of the prism (faces from
/// kPrismTriangleCorners, outward normals). A face with a zero normal makes the prism count
/// as empty: a collapsed prism would otherwise pass unbounded points.
inline bool InsidePrism(const std::array<Eigen::Vector3d, 6>& prism, const Eigen::Vector3d& p) {
  for (size_t f = 0; f < kPrismTriangleCorners.size(); f += 3) {
    const Eigen::Vector3d& p0 = prism[kPrismTriangleCorners[f]];
    const Eigen::Vector3d& p1 = prism[kPrismTriangleCorners[f + 1]];
    const Eigen::Vector3d& p2 = prism[kPrismTriangleCorners[f + 2]];
    if (!((p1 - p0).cross(p2 - p0).norm() > 0)) return false;
    if (Orientation(p0, p1, p2, p) > 0) return false;
  }
  return true;
}

/// Returns whether p is in the union of the bounded exact offset's pieces.
inline bool InsideBoundedExactOffset(const BoundedExactOffset& offset, const Eigen::Vector3d& p) {
  for (const Obb& box : offset.edge_boxes) {
    if (InsideObb(box, p)) return true;
  }
  return InsidePrism(offset.prism, p);
}

}  // namespace far::test
