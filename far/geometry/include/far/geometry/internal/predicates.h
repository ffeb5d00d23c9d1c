#pragma once

// Exact geometric predicates on double input: the sign of an orientation determinant is
// decided by a floating-point evaluation with a semi-static error bound (Shewchuk, "Adaptive
// precision floating-point arithmetic and fast robust geometric predicates", 1997, stage A),
// and, only when the bound cannot certify the sign, by exact expansion arithmetic.
//
// Exactness holds for finite input whose arithmetic neither overflows nor underflows, which is
// guaranteed when (i) every nonzero coordinate lies in [2^-300, 2^300] in magnitude (about
// 5e-91 to 2e90), so that every component of the exact fallback is a multiple of 2^-1056 and
// no error-free product loses bits, and (ii) every nonzero difference of two coordinates is at
// least 2^-330 (about 5e-100), so that the filter's products stay normal. Subnormal input (for
// example nextafter(0.0, 1.0)) is outside this range and may be misjudged.
//
// The filters assume that every a * b + c is rounded twice. PlaneSide::Side is inline, so a
// translation unit that includes this header must not contract it into an fma either: the
// project compiles ISO C++ (CMAKE_CXX_EXTENSIONS OFF), where GCC's default is
// -ffp-contract=off, and never uses -ffast-math.
//
// These are far::internal: visible to tests and to the other far areas, not part of the API.

#include <cmath>

#include <Eigen/Core>

namespace far::internal {

/// Returns the sign (-1, 0, +1) of det[b - a, c - a, d - a] = ((b - a) x (c - a)) . (d - a):
/// +1 when d lies on the side of the plane through a, b, c that its right-handed normal
/// (b - a) x (c - a) points to, 0 when the four points are coplanar. Exact (see above).
int Orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d);

/// Returns the sign of (b - a) x (c - a) in the plane: +1 when a, b, c turn counterclockwise,
/// 0 when they are collinear. Exact.
int Orient2d(double ax, double ay, double bx, double by, double cx, double cy);

/// Returns Orient2d of the projections of a, b, c onto the coordinate plane (axis i, axis j).
/// With (i, j) = (1, 2), (2, 0), (0, 1) this is the sign of the x, y, z component of
/// (b - a) x (c - a). @pre i, j in {0, 1, 2}.
inline int Orient2dProjected(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, int i, int j) {
  return Orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/// Returns true iff a, b, c lie on one line (coincident points included). Exact.
bool Collinear3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// The oriented plane of a triangle (a, b, c), prepared once so that many points can be
/// classified against it: Side(d) == Orient3d(a, b, c, d), exactly, but the shared part of the
/// floating-point filter is computed only once. Keeps references: a, b, c must outlive *this*.
class PlaneSide {
 public:
  PlaneSide(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

  /// Returns Orient3d(a, b, c, d).
  int Side(const Eigen::Vector3d& d) const {
    const double wx = d.x() - a_.x();
    const double wy = d.y() - a_.y();
    const double wz = d.z() - a_.z();
    const double det = wx * normal_.x() + wy * normal_.y() + wz * normal_.z();
    const double permanent = std::abs(wx) * permanent_.x() + std::abs(wy) * permanent_.y() +
                             std::abs(wz) * permanent_.z();
    const double bound = kOrient3dBoundA * permanent;
    if (det > bound) return 1;
    if (-det > bound) return -1;
    return SideExact(d);
  }

  /// The floating-point value of Orient3d(a, b, c, d)'s determinant, and in `bound` the filter's
  /// bound on its error: |value - det| <= bound.
  double Value(const Eigen::Vector3d& d, double& bound) const {
    const double wx = d.x() - a_.x();
    const double wy = d.y() - a_.y();
    const double wz = d.z() - a_.z();
    const double permanent = std::abs(wx) * permanent_.x() + std::abs(wy) * permanent_.y() +
                             std::abs(wz) * permanent_.z();
    bound = kOrient3dBoundA * permanent;
    return wx * normal_.x() + wy * normal_.y() + wz * normal_.z();
  }

  /// Shewchuk's o3derrboundA = (7 + 56 eps) eps with eps = 2^-53.
  static constexpr double kOrient3dBoundA = (7.0 + 56.0 * 0x1p-53) * 0x1p-53;

 private:
  int SideExact(const Eigen::Vector3d& d) const;

  const Eigen::Vector3d& a_;
  const Eigen::Vector3d& b_;
  const Eigen::Vector3d& c_;
  Eigen::Vector3d normal_;     // fl((b - a) x (c - a)), each component a difference of products
  Eigen::Vector3d permanent_;  // per component, the sum of the magnitudes of those two products
};

/// Orient3dValue against one plane for many points, with the plane's share of the work (its
/// edge differences and their cross product in double-double) done once. Keeps references:
/// a, b, c must outlive *this.
class PlaneValue {
 public:
  PlaneValue(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);
  /// Orient3dValue(a, b, c, d): within 2^-51 relative, zero exactly when coplanar.
  double Value(const Eigen::Vector3d& d) const;

 private:
  const Eigen::Vector3d& a_;
  const Eigen::Vector3d& b_;
  const Eigen::Vector3d& c_;
  bool exact_edges_ = false;  // b - a and c - a are exact in double
  double normal_hi_[3] = {0, 0, 0}, normal_lo_[3] = {0, 0, 0}, normal_permanent_[3] = {0, 0, 0};
};

/// Returns (b - a) x (d - c) with every component accurate to a relative error of at most
/// 2^-52 and exactly zero iff the two difference vectors are parallel or one is zero: from the
/// exact expansion, or, where both differences are exact in double, from Kahan's 2x2
/// determinant with a fused multiply-add (the same bound). Used where a direction must be
/// accurate to a few ulps even for slivers and nearly parallel edges.
Eigen::Vector3d RoundedCross(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, const Eigen::Vector3d& d);

/// det[b - a, c - a, d - a] (Orient3d's determinant) as a double within a relative error of
/// 2^-51: the floating-point value where its error bound certifies that, else the exact
/// expansion, compressed and rounded. Zero exactly when the points are coplanar; its sign is
/// Orient3d's. What constructions use (contact points), where the predicates need only signs.
double Orient3dValue(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d);

/// (b - a) x (c - a) in the plane, as Orient3dValue: within a relative error of 2^-51, zero
/// exactly when collinear.
double Orient2dValue(double ax, double ay, double bx, double by, double cx, double cy);

/// The exact fallbacks, exposed so that tests can check them without the filter.
int Orient3dExact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d);
int Orient2dExact(double ax, double ay, double bx, double by, double cx, double cy);

}  // namespace far::internal
