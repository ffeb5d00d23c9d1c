#pragma once

// How deep two closed objects in contact interpenetrate: the deepest vertex of either inside the
// other, decided exactly, and its distance to the other's surface (docs/contact-geometry.md,
// "Penetration depth", says what the number means and where it is not the true depth).

#include <cstddef>
#include <span>

#include "far/model/contact_geometry.h"
#include "far/model/mesh.h"
#include "far/pairs/world_object.h"

namespace far {

/// True iff the mesh is closed: no triangle repeats an index, and every edge is used by exactly
/// two triangles that traverse it in opposite directions (watertight and consistently
/// oriented; outward or inward alike). Topology only: a closed mesh may still pass through
/// itself. @pre indices < num_vertices. O(n log n).
bool IsClosedMesh(std::span<const TriangleIndices> triangles, size_t num_vertices);

/// The penetration of objects a and b (world views), each `closed` as IsClosedMesh says. Not
/// both closed: a Penetration with closed false and zeros. Otherwise the deepest vertex v of
/// either object strictly inside the other (exact parity of a ray's crossings with the other's
/// triangles), with depth = its distance to the other's surface, point_a and point_b the vertex
/// and its closest surface point (each on its own object), direction = (point_a - point_b) /
/// depth; depth 0 and zero vectors when no vertex is strictly inside. object_a and object_b
/// are left for the caller. Thread-safe (pure function).
Penetration MeasurePenetration(const WorldObjectView& a, bool a_closed, const WorldObjectView& b,
                               bool b_closed);

}  // namespace far
