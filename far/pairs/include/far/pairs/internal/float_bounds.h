#pragma once

// Rounding a bound outward to float: the hierarchy stores its slabs' bounds in float
// (TriangleBvh::Slab), and a bound rounded the wrong way could separate a triangle from itself.
//
// Without a branch on the direction round-to-nearest went: it goes either way at random, and a
// branch on it mispredicted so often that TriangleBvh::Build was a fifth slower
// (far_bvh_benchmark BM_Hierarchy_Build/20000: 6.7 ms with plain casts, 8.2 with the branch,
// 8.7 with std::nextafter, a library call around which the compiler saves every register; 6.9
// with this).
//
// far::internal: visible to tests, not part of the API.

#include <cmath>
#include <limits>

namespace far::internal {

/// A float <= x, at most three floats below x (-infinity below float's range; NaN stays NaN).
/// x less at least one float ulp of itself and the smallest subnormal float, then rounded to
/// nearest, which moves it by at most half an ulp: below x (two floats below at most, three near
/// the smallest normal float). The double arithmetic's own rounding is 2^-30 of that step.
inline float FloatBelow(double x) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (x > kMax) return std::numeric_limits<float>::max();  // +infinity too
  const double below = x - (std::abs(x) * 0x1p-23 + 0x1p-149);
  if (below < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(below);
}

/// A float >= x, at most three floats above x (+infinity above float's range; NaN stays NaN).
inline float FloatAbove(double x) { return -FloatBelow(-x); }

}  // namespace far::internal
