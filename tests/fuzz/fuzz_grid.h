#pragma once

// Shared by the culling oracles (bvh_reference, cpu_methods, gl_methods): how their bytes become
// geometry. Corners lie on a grid, so that corners, edges and planes of different objects
// coincide exactly (touching, coplanar and degenerate triangles); one byte picks the scale, from
// ordinary ones to tiny ones around the pipeline's flush of world coordinates; another may move
// the whole scene far from the origin.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz_input.h"
#include <Eigen/Core>

#include "far/model/contact_pair.h"

namespace far::fuzz {

/// The scene's scale from an int8 exponent e: 2^clamp(e, -20, 10), or 2^(e - 188) for e < -64
/// (2^-316 to 2^-253: with grid corners up to 128 steps of scale / 16, corners from 2^-320 to
/// 2^-250, the largest around kTinyWorldCoordinate = 2^-256, the rest below).
inline double GridScale(int exponent) {
  return std::ldexp(1.0, exponent < -64 ? exponent - 188 : std::clamp(exponent, -20, 10));
}

/// Shift s (0-7) of a whole scene from the origin, along (1, -0.5, 0.25).
inline Eigen::Vector3d GridShift(int s) {
  constexpr std::array<double, 8> kShifts = {0, 1e3, -3e4, 1e5, 1e6, -1e6, 1e7, 0.5};
  return kShifts[s & 7] * Eigen::Vector3d(1, -0.5, 0.25);
}

/// A grid point: int8 x 3, in grid steps.
inline Eigen::Vector3d GridPoint(FuzzInput& in, double step) {
  const double x = in.Take<int8_t>(), y = in.Take<int8_t>(), z = in.Take<int8_t>();
  return Eigen::Vector3d(x, y, z) * step;
}

/// The triangle pairs of distance pairs (their distances are each method's own bounds).
template <typename Object>
std::vector<BasicContactPair<Object>> PairsOf(const std::vector<BasicDistancePair<Object>>& list) {
  std::vector<BasicContactPair<Object>> pairs;
  for (const auto& d : list) pairs.push_back(d.pair);
  return pairs;
}

}  // namespace far::fuzz
