#pragma once

#include <optional>

#include <Eigen/Core>

namespace far {

/// A triangle given by its three corners (world frame unless said otherwise).
struct TrianglePoints {
  Eigen::Vector3d a, b, c;
};

/// Returns true iff the closed triangles `s` and `t` share at least one point (touching counts).
/// Exact for the double input: every decision is an orientation predicate evaluated with a
/// floating-point filter and an exact fallback, so coplanar pairs, shared vertices and edges,
/// vertex-on-face and degenerate triangles (treated as the segment or point they are) are
/// answered exactly. @pre all coordinates finite. Thread-safe (pure function).
bool TrianglesIntersect(const TrianglePoints& s, const TrianglePoints& t);

/// TrianglesIntersect for a caller that has already found the two triangles' closed bounding
/// boxes to share a point (it skips that first check). The same answer for such a pair.
bool TrianglesIntersectWithinBoxes(const TrianglePoints& s, const TrianglePoints& t);

/// Returns the Euclidean distance between the closed triangles `s` and `t` (0 if they
/// intersect), computed in double. Stable for near-parallel and degenerate triangles. Symmetric
/// bit for bit: (s, t) and (t, s) give the same value (so do the two functions below).
/// @pre all coordinates finite. Thread-safe.
double TriangleDistance(const TrianglePoints& s, const TrianglePoints& t);

/// Returns true iff distance(s, t) <= max_distance, up to the error bound documented in
/// triangle_distance.cc (intersecting triangles are always within). @pre max_distance >= 0.
bool TrianglesWithinDistance(const TrianglePoints& s, const TrianglePoints& t, double max_distance);

/// Both at once: TriangleDistance(s, t) when TrianglesWithinDistance(s, t, max_distance), else
/// nullopt. One intersection test and one distance evaluation where the two calls make two each
/// (a distance query reports the distance of every pair it accepts). @pre max_distance >= 0.
std::optional<double> TriangleDistanceIfWithin(const TrianglePoints& s, const TrianglePoints& t,
                                               double max_distance);

}  // namespace far
