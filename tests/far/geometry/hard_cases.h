#pragma once

// The hard-case suite for exact triangle-triangle tests: pairs constructed deliberately at the
// edge of floating-point reasoning (coplanar overlap / touch / near miss, shared vertices and
// edges, vertex on face, edge-edge crossings, slivers with aspect ratio 1e8, collinear and point
// triangles, coordinates at 1e5 and 1e6 with features of 1e-3, separations of one ulp and of
// 1e-9 relative). Shared by the unit tests, the FCL comparison benchmark and later GPU tests.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "far/geometry/triangle_tests.h"

namespace far::reference {

/// The triangle (a, b, c): the suite's and the tests' shorthand.
inline TrianglePoints Tri(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c) {
  return {a, b, c};
}

/// One hard pair of triangles.
struct HardCase {
  std::string name;      ///< "<base>@<transform>[<variant>]", e.g. "sliver_apex_touch@1e6+ulp"
  std::string category;  ///< the base's family, e.g. "coplanar", "sliver", "collinear"
  TrianglePoints s, t;
  bool intersect = false;        ///< the exact answer (ExactTrianglesIntersect)
  std::optional<bool> intended;  ///< what the construction meant, when that is certain
};

/// Builds the suite (a few hundred cases; deterministic). Each case's `intersect` is computed
/// by the exact rational reference.
std::vector<HardCase> MakeHardCases();

/// Returns the 72 relabelings of a pair: the 6 vertex orders of s times the 6 of t (both
/// orientations), each also with s and t swapped. The exact answer is the same for all.
std::vector<std::pair<TrianglePoints, TrianglePoints>> Relabelings(const TrianglePoints& s,
                                                                   const TrianglePoints& t);

}  // namespace far::reference
