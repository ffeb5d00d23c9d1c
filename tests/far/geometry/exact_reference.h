#pragma once

// The exact reference for triangle tests, in rational arithmetic (GMP's mpq_class): used only
// by tests, benchmarks and studies, never by the library. It is deliberately an independent
// implementation: it constructs points and parameters exactly (segment/plane clipping, exact
// barycentric and parametric tests) instead of reusing far::internal's orientation predicates,
// so that the two can disagree if either is wrong. Slow (tens of microseconds per pair).

#include <vector>

#include <gmpxx.h>

#include "far/geometry/triangle_tests.h"

namespace far::reference {

/// A point or vector with exact rational coordinates.
struct QVec {
  mpq_class x, y, z;
};

/// Returns the exact rational value of a double point (every finite double is a rational).
QVec ToQ(const Eigen::Vector3d& p);

/// Returns the sign of det[b - a, c - a, d - a], computed exactly.
int ExactOrient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d);

/// Returns the sign of (b - a) x (c - a) in the plane, computed exactly.
int ExactOrient2d(double ax, double ay, double bx, double by, double cx, double cy);

/// Returns true iff the closed triangles (convex hulls of their three points, so degenerate
/// triangles are the segment or point they are) share a point. Exact.
bool ExactTrianglesIntersect(const TrianglePoints& s, const TrianglePoints& t);

/// Returns the extreme points of the intersection of the closed triangles (degenerate ones are
/// the segment or point they are), exactly: none when they are disjoint, one when they touch at
/// a point, a segment's two ends, or a coplanar overlap polygon's vertices (collinear boundary
/// points dropped), each once. Built from the edges of each clipped to the other.
std::vector<QVec> ExactIntersectionExtremes(const TrianglePoints& s, const TrianglePoints& t);

/// Returns the exact squared Euclidean distance of the closed triangles (0 if they intersect).
mpq_class ExactSquaredDistance(const TrianglePoints& s, const TrianglePoints& t);

}  // namespace far::reference
