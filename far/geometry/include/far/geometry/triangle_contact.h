#pragma once

// The geometry of one triangle pair: where two intersecting triangles meet, and the closest
// points of two triangles. Every decision (which edge crosses which plane, which point lies
// inside which triangle, where two points coincide) is an exact predicate; every point is then
// constructed once from exactly known quantities, so its error is a few units in the last place
// of the triangles' coordinates (docs/culling.md, "Contact geometry", gives the bound).

#include "far/geometry/triangle_tests.h"
#include "far/model/contact_geometry.h"

namespace far {

/// Where the closed triangles `s` and `t` meet: one point, a segment's two endpoints, or the
/// overlap polygon of coplanar triangles; and their unit normals. Degenerate triangles are the
/// segment or point they are. @pre TrianglesIntersect(s, t), all coordinates finite (and in the
/// range of far/geometry's predicates.h). Thread-safe (pure function).
ContactGeometry TriangleContactGeometry(const TrianglePoints& s, const TrianglePoints& t);

/// A pair of closest points of the closed triangles `s` and `t` (point_a on s, point_b on t);
/// for intersecting triangles a common point. Thread-safe.
ClosestPoints TriangleClosestPoints(const TrianglePoints& s, const TrianglePoints& t);

/// TriangleClosestPoints for a caller that knows the triangles are disjoint (a distance pair
/// reported with a distance above 0): the same points, without the intersection test.
/// @pre !TrianglesIntersect(s, t).
ClosestPoints DisjointClosestPoints(const TrianglePoints& s, const TrianglePoints& t);

}  // namespace far
