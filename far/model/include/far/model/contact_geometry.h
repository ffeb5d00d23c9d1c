#pragma once

// The geometry a step reports when StepRequest::geometry asks for it: where the triangles of a
// contact meet, the closest points of a distance pair, and how deep two closed objects
// interpenetrate. Every point is in the world frame. docs/culling.md ("Contact geometry") gives
// the error bounds and what each number means.

#include <array>
#include <cstdint>

#include <Eigen/Core>

namespace far {

/// Where the two triangles of one contact meet. A contact's triangles share at least one point;
/// their intersection is a point, a segment, or (coplanar triangles) a convex polygon.
struct ContactGeometry {
  /// The most points an intersection has: two coplanar triangles overlap in at most a hexagon.
  static constexpr int kMaxPoints = 6;
  /// 1: they touch at one point; 2: the intersection segment's endpoints; 3 to 6: the vertices
  /// of the overlap polygon of coplanar triangles, counterclockwise about normal_a (2 when the
  /// overlap of coplanar triangles is a segment, 1 when a point).
  int num_points = 0;
  std::array<Eigen::Vector3d, kMaxPoints> points{};
  /// Each triangle's unit normal, (b - a) x (c - a) normalized (the right-hand rule on the
  /// mesh's vertex order); zero for a degenerate triangle (collinear or coincident corners).
  Eigen::Vector3d normal_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_b = Eigen::Vector3d::Zero();
  /// True when both triangles lie in one plane (the points are then an overlap polygon).
  bool coplanar = false;
};

/// The two closest points of a distance pair, one on each triangle: |point_b - point_a| is the
/// pair's distance (up to the bound in docs/culling.md). When the closest points are not unique
/// (parallel edges or faces), one such pair.
struct ClosestPoints {
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();
};

/// How deep two objects in contact interpenetrate (one entry per object pair with contacts,
/// object_a < object_b). Defined only when both meshes are closed (docs/contact-geometry.md,
/// "Penetration depth", says how that is decided, what depth means, where it is not the true
/// penetration depth, and its error bound); otherwise `closed` is false and the rest is zero.
struct Penetration {
  uint32_t object_a = 0;
  uint32_t object_b = 0;
  bool closed = false;
  /// The deepest vertex of either object inside the other, decided by exact inside tests, and
  /// its distance to the other object's surface: depth >= 0 (0 when no vertex is strictly
  /// inside, for example two boxes touching face to face or crossing edge through edge).
  double depth = 0;
  /// The unit vector of point_a - point_b ((point_a - point_b) / depth up to rounding): moving
  /// object_b by depth * direction carries point_b onto point_a, which brings the deepest
  /// vertex to the other object's surface. Zero when depth is 0.
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  /// Witness points: the deepest vertex (of either object) and its closest point on the other
  /// object's surface; point_a lies on object_a (its vertex or surface), point_b on object_b.
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();
};

}  // namespace far
