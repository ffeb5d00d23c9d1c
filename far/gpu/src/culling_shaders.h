#pragma once

// The culling shaders: one vertex shader that builds each piece corner on the GPU, and one
// fragment shader per role a draw plays in a view. Private to far::gpu.

#include <cstdint>
#include <span>
#include <string>

#include "far/gpu/culling_renderer.h"

namespace far::internal {

// What the fragment shader does in each draw of a view.
enum class FragmentRole {
  kWriteId,     // ID pass 1: nearest front face per pixel, writes its group id
  kOtherDepth,  // ID pass 2: nearest front face of any group other than pass 1's
  kFlag,        // ID pass 3: back faces behind another group's nearest front face flag
  kDepthOnly,   // occlusion queries: depth only
};
constexpr int kNumRoles = 4;

/// The geometric shape of a piece set's instances.
enum class Shape { kBox, kPrism, kTriangle };
constexpr int kNumShapes = 3;

/// The shape each piece set draws.
Shape ShapeOf(PieceSet set);

/// Triangle corners of one instance, as indices into its distinct corners (8 for a box, 6 for
/// a prism, 3 for a triangle).
std::span<const uint8_t> CornerIndices(Shape shape);

/// The GLSL 4.50 source of the vertex (`vertex` true) or fragment shader for `shape` and `role`.
std::string ShaderSource(Shape shape, FragmentRole role, bool vertex);

}  // namespace far::internal
