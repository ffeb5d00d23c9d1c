#pragma once

// Mesh building blocks shared by the scene generators (private to far::scenes): tubes, surfaces
// of revolution, grids, height fields, fracturing, placing a rigid body so that it touches a
// height field, and the generators' random numbers.

#include <cstdint>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/mesh.h"
#include "far/model/pose.h"

namespace far::scenes::internal {

/// Seconds between two frames of every generated scene.
inline constexpr double kFrameSeconds = 0.1;

/// Triangles that AppendTube adds.
int TubeTriangles(int sides, int segments);

/// Appends a closed tube from `a` (radius r_a) to `b` (radius r_b): `sides` around, `segments`
/// rings along, each end capped by a fan to its center. Outward-facing.
void AppendTube(Mesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r_a,
                double r_b, int sides, int segments);

/// Returns the triangles of a grid of cells x cells quads over (cells + 1)^2 vertices numbered row
/// by row (vertex (i, j) is i * (cells + 1) + j), two per quad, split by the (i, j)-(i + 1, j + 1)
/// diagonal.
std::vector<TriangleIndices> GridTriangles(int cells);

/// A closed surface of revolution about z: a pole at z_bottom, rings (radius[i], z[i]) for the
/// profile points in order of increasing z, a pole at z_top. 2 * slices * profile.size()
/// triangles. Outward-facing.
Mesh LatheMesh(std::span<const Eigen::Vector2d> radius_z, double z_bottom, double z_top,
               int slices);

/// A height field z = h(x, y) over a rectangle, sampled at the corners of cells_x x cells_y cells
/// and triangulated with the diagonal from (i, j) to (i + 1, j + 1). Height() is the height of
/// that triangulated surface (not of h), so that placing a body against it is exact.
class HeightField {
 public:
  template <typename H>
  HeightField(const Eigen::Vector2d& min, const Eigen::Vector2d& max, int cells_x, int cells_y, H h)
      : min_(min), max_(max), cells_x_(cells_x), cells_y_(cells_y) {
    step_ = (max - min).cwiseQuotient(Eigen::Vector2d(cells_x, cells_y));
    z_.resize(static_cast<size_t>(cells_x + 1) * static_cast<size_t>(cells_y + 1));
    for (int j = 0; j <= cells_y; ++j) {
      for (int i = 0; i <= cells_x; ++i) z_[Index(i, j)] = h(X(i), Y(j));
    }
  }

  /// The triangulated surface, 2 * cells_x * cells_y triangles, facing +z.
  Mesh ToMesh() const;
  /// Height of the triangulated surface at (x, y), clamped to the rectangle.
  double Height(double x, double y) const;
  const Eigen::Vector2d& min() const { return min_; }
  const Eigen::Vector2d& max() const { return max_; }

 private:
  size_t Index(int i, int j) const {
    return static_cast<size_t>(j) * static_cast<size_t>(cells_x_ + 1) + static_cast<size_t>(i);
  }
  double X(int i) const { return i == cells_x_ ? max_.x() : min_.x() + i * step_.x(); }
  double Y(int j) const { return j == cells_y_ ? max_.y() : min_.y() + j * step_.y(); }

  Eigen::Vector2d min_, max_, step_;
  int cells_x_, cells_y_;
  std::vector<double> z_;
};

/// Returns the pose with `rotation` and horizontal position `xy` whose height puts the lowest
/// point of `p_OV` (relative to the height field below it) `depth` under the ground: the body
/// then crosses the ground (a contact) as long as it is taller than `depth` and stays over the
/// height field's rectangle.
Pose RestOn(const HeightField& ground, std::span<const Eigen::Vector3d> p_OV,
            const Eigen::Quaterniond& rotation, const Eigen::Vector2d& xy, double depth);

/// One piece of a fractured mesh, in its own frame F (origin at the piece's vertex centroid).
struct Fragment {
  Mesh mesh;               ///< vertices in frame F
  Eigen::Vector3d p_OF{};  ///< origin of F in the frame O of the mesh that was broken
};

/// Breaks `mesh` (in frame O) into `num_pieces` pieces: each triangle goes to the nearest of
/// `num_pieces` distinct random seed triangles (by centroid: Voronoi cells on the surface), and
/// each piece is closed by a fan from its boundary edges to an apex between its centroid and
/// `core`, so that the pieces are solid-looking wedges. Every piece is non-empty.
std::vector<Fragment> Fracture(const Mesh& mesh, int num_pieces, const Eigen::Vector3d& core,
                               std::mt19937_64* rng);

/// The random numbers of one scene: one generator seeded once, drawn from in the order of the
/// calls, so that a generator split into helpers draws what it drew in one piece (pass it by
/// pointer; never copy it). Draws that are arguments of one call, as in
/// Eigen::Vector2d(Uniform(..), Uniform(..)), come in the order the compiler picks (GCC 12: the
/// last argument first; Clang: the first), so GCC and Clang builds make different scenes from
/// one seed; the generators keep such calls as written, so that the scenes of a GCC build (the
/// studies') do not change.
class Random {
 public:
  explicit Random(uint64_t seed) : rng_(seed) {}
  Random(const Random&) = delete;
  Random& operator=(const Random&) = delete;

  /// Draws a number uniform in [0, 1).
  double Unit() { return unit_(rng_); }
  /// Draws a number uniform in [lo, hi), as lo + (hi - lo) * Unit().
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Unit(); }
  /// Returns the generator itself, for helpers that draw on their own (Fracture).
  std::mt19937_64* engine() { return &rng_; }

 private:
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
};

/// A unit quaternion from a rotation vector (angle * axis); identity for zero.
Eigen::Quaterniond RotationVector(const Eigen::Vector3d& angle_axis);

/// A pose from a translation and a rotation (normalized).
Pose MakePose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation);

/// The vertex update of a deformable object: new positions, the object's triangles.
std::pair<uint32_t, Mesh> VertexUpdate(uint32_t id, std::vector<Eigen::Vector3d> p_MV,
                                       const std::vector<TriangleIndices>& triangles);

}  // namespace far::scenes::internal
