#pragma once

// How deep two closed objects in contact interpenetrate: the deepest vertex of either inside the
// other, decided exactly, and its distance to the other's surface (docs/contact-geometry.md,
// "Penetration depth", says what the number means and where it is not the true depth).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "far/geometry/triangle_tests.h"
#include "far/model/contact_geometry.h"
#include "far/model/contact_pair.h"
#include "far/model/mesh.h"
#include "far/pairs/triangle_bvh.h"
#include "far/pairs/world_object.h"

namespace far {

/// True iff the mesh is closed: no triangle repeats an index, and every edge is used by exactly
/// two triangles that traverse it in opposite directions (watertight and consistently
/// oriented; outward or inward alike). Topology only: a closed mesh may still pass through
/// itself. @pre indices < num_vertices. O(n log n).
bool IsClosedMesh(std::span<const TriangleIndices> triangles, size_t num_vertices);

/// One closed object's surface prepared for MeasurePenetration: a hierarchy of its world
/// triangles (built once, then shared by every pair the object is in). The view's vertices and
/// triangles must outlive it. Thread safety: const use from many threads.
struct PenetrationSurface {
  explicit PenetrationSurface(const WorldObjectView& view);
  TrianglePoints Triangle(size_t t) const;
  /// A lower bound of the distance from v to triangle t's plane, less than TriangleDistance's
  /// value for v and t (0 or less for a degenerate triangle): what prunes nearest-point queries.
  double PlaneGap(size_t t, const Eigen::Vector3d& v) const;

  WorldObjectView view;  ///< spans into the caller's vertices and triangles
  TriangleBvh bvh;
  Eigen::AlignedBox3d box;
  std::vector<uint8_t> degenerate;            ///< by triangle: collinear corners (no interior)
  std::vector<Eigen::Vector3d> unit_normals;  ///< by triangle; zero when degenerate
  std::vector<double> extents;  ///< by triangle: |b - a|_1 + |c - a|_1 (PlaneGap's slack)
  double margin = 0;            ///< node boxes are grown by this (their rounding)
  std::vector<uint32_t> neighbor_offsets, neighbors;  ///< vertex neighbors by edge (CSR)
  std::vector<uint32_t> part_representatives;         ///< one vertex per connected part
};

/// MeasurePenetration of two closed objects' prepared surfaces. With `contacts` (every
/// intersecting triangle pair of a and b: triangle_a in a, triangle_b in b), only the vertices
/// that can be inside are located: those reachable from the contacts' triangles, and from one
/// vertex of each connected part of a mesh, through vertices inside. That finds every vertex
/// inside: an edge from a vertex inside to one that is not meets the other's surface, so its
/// triangles are in the contacts; a part with no such edge is wholly inside or outside, and its
/// one vertex says which. Empty `contacts`: every vertex is located (the reference).
Penetration MeasurePenetration(const PenetrationSurface& a, const PenetrationSurface& b,
                               std::span<const ContactPair> contacts);

/// The penetration of objects a and b (world views), each `closed` as IsClosedMesh says. Not
/// both closed: a Penetration with closed false and zeros. Otherwise the deepest vertex v of
/// either object strictly inside the other (exact parity of a ray's crossings with the other's
/// triangles), with depth = its distance to the other's surface, point_a and point_b the vertex
/// and its closest surface point (each on its own object), direction = the unit vector of
/// point_a - point_b; depth 0 and zero vectors when no vertex is strictly inside. object_a and
/// object_b are left for the caller. Thread-safe (pure function).
Penetration MeasurePenetration(const WorldObjectView& a, bool a_closed, const WorldObjectView& b,
                               bool b_closed);

}  // namespace far
