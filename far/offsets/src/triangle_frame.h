#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace far::internal {

/// Unit roundoff of double: |fl(x op y) - (x op y)| <= kDoubleUnit |fl(x op y)|.
inline constexpr double kDoubleUnit = 0x1p-53;

/// Relative inflation (32 units of roundoff) that makes a computed box contain what it must
/// despite the rounding of its own construction and of a caller's membership test.
inline constexpr double kInflation = 0x1p-48;

/// Returns x >= 0 rounded up by kInflation: larger than x by more than any rounding error of
/// the handful of operations that produced it or that a caller applies to it.
inline double RoundUp(double x) { return x + kInflation * x; }

/// Returns |x| (Euclidean) without overflow or underflow for any finite x.
double SafeNorm(const Eigen::Vector3d& x);

/// Returns x / |x| computed without overflow or underflow. @pre x != 0, finite.
Eigen::Vector3d SafeNormalized(const Eigen::Vector3d& x);

/// Returns the unit vector perpendicular to unit `u` obtained by crossing u with the world
/// axis on which |u| has its smallest component (lowest index on ties): deterministic.
Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& u);

/// The orthonormal frame of a triangle shared by its rectangle (UOBB) and its bounded exact
/// offset, with what is known about its accuracy.
struct TriangleFrame {
  std::array<Eigen::Vector3d, 3> vertices;  ///< a, b, c
  /// Columns u, v, n: u along the longest edge, n the unit normal (oriented so that a, b, c
  /// is counter-clockwise seen from +n) or, for a degenerate triangle, a deterministic unit
  /// vector perpendicular to u; v = n x u. Identity when a == b == c.
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  int longest = 0;    ///< the longest edge: i runs from vertices[i] to vertices[(i+1)%3]
  double length = 0;  ///< its length L
  /// Upper bound on the angle (radians) between n and the exact triangle's normal; +inf when
  /// n is not a measured normal (degenerate triangle, fallback perpendicular).
  double tilt_bound = 0;
  /// Upper bound on the distance of every triangle point from the longest edge (segment).
  double height = 0;
  /// Absolute slack (world units) that covers the rounding of every construction from this
  /// frame and of a caller's membership test: kInflation (max |coordinate| + L).
  double slack = 0;
};

/// Computes the frame of triangle (a, b, c). Finite for any finite input whose coordinate
/// differences are finite; never NaN.
TriangleFrame ComputeTriangleFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c);

}  // namespace far::internal
