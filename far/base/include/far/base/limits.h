#pragma once

// Every limit on what a client, a scene file or a caller may ask of far, named once. The
// pipeline, the scene model, the protocol's validation and the daemon all check against these.

#include <cstddef>
#include <cstdint>

namespace far {

/// Object ids: every uint32, 0 and 2^32 - 1 included, in scene files, the update ring, the
/// pipeline and replies alike.
inline constexpr uint32_t kMinObjectId = 0;
inline constexpr uint32_t kMaxObjectId = UINT32_MAX;

/// The most vertices or triangles one mesh may hold: Mesh::num_vertices() and num_triangles()
/// return int.
inline constexpr uint64_t kMaxMeshElements = 0x7fffffff;

/// Step requests: the viewport is resolution x resolution pixels.
inline constexpr int kMinResolution = 8;
inline constexpr int kMaxResolution = 8192;
/// Triangles per sub-object (k).
inline constexpr int kMaxSubobjectSize = 1 << 20;
/// Coordinates: every vertex position and translation has |x|, |y|, |z| <= this (world units), in
/// scene files, the update ring and the pipeline alike. World coordinates then stay below
/// 3e12 (|R p + t|), far inside the range where the exact predicates are exact (2^300).
inline constexpr double kMaxCoordinate = 1e12;
/// The largest distance D of a localized distance query (world units).
inline constexpr double kMaxDistance = 1e12;

/// Method 'exact' (the brute-force reference tests every cross-object triangle pair) is refused
/// on scenes with more pairs than this: about 10 s on two cores. 'bvh' gives the same answer.
inline constexpr uint64_t kMaxBruteForcePairs = uint64_t{1} << 30;

/// Scene objects' optional names (labels for people): at most this many bytes, one line.
inline constexpr size_t kMaxObjectNameBytes = 100;

/// Poses: a rotation quaternion is accepted when | |q| - 1 | <= this, then normalized. Wide
/// enough for quaternions written with four decimals ([0.7071, 0, 0, 0.7071] is off by 1e-5),
/// narrow enough that a quaternion that is not a rotation at all (a typo, a missing component,
/// Euler angles) is refused rather than silently turned into some rotation.
inline constexpr double kQuaternionTolerance = 1e-3;

}  // namespace far
