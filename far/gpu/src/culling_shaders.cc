#include "culling_shaders.h"

#include <array>

#include "far/offsets/bounding_offset.h"

namespace far::internal {
namespace {

// The vertex shader builds each corner of an instance from the per-object data: its matrix
// (anchor frame -> clip space, composed in double on the CPU) and its radius (r plus the
// object's float rounding bound), so offsets never need recomputing when r changes.
const char* kVertexShader = R"(
layout(location = 0) in vec3 p0;
layout(location = 1) in vec3 p1;
layout(location = 2) in vec3 p2;
layout(location = 3) in vec3 p3;
layout(location = 4) in uint triangle;
layout(location = 5) in uint slot;

struct ObjectData { mat4 M; float radius; uint group; uint first_primitive; uint in_view; };
layout(std430, binding = 0) readonly buffer Objects { ObjectData objects[]; };
layout(std430, binding = 1) readonly buffer Alive { uint alive[]; };

uniform int triangles_per_primitive;  // 0: one primitive per object

flat out uint v_group;
flat out uint v_primitive;

void main() {
  ObjectData o = objects[slot];
  uint primitive = o.first_primitive +
      (triangles_per_primitive > 0 ? triangle / uint(triangles_per_primitive) : 0u);
  v_group = o.group;
  v_primitive = primitive;
  // Objects outside this view and pruned primitives are sent behind the far plane (clipped).
  if (o.in_view == 0u || alive[primitive] == 0u) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
    return;
  }
  uint k = uint(gl_VertexID);  // the corner: indexed draws over the distinct corners
  vec3 p;
#if SHAPE_BOX
  vec3 s = vec3((k & 1u) != 0u ? 1.0 : -1.0, (k & 2u) != 0u ? 1.0 : -1.0, (k & 4u) != 0u ? 1.0 : -1.0);
  vec3 h = p3 + vec3(o.radius);
  p = p0 + (s.x * h.x) * p1 + (s.y * h.y) * p2 + (s.z * h.z) * cross(p1, p2);
#elif SHAPE_PRISM
  uint corner = k % 3u;
  vec3 base = corner == 0u ? p0 : (corner == 1u ? p1 : p2);
  p = base + (k < 3u ? o.radius : -o.radius) * p3;
#else
  p = k == 0u ? p0 : (k == 1u ? p1 : p2);
#endif
  gl_Position = o.M * vec4(p, 1.0);
}
)";

const char* kFragmentShader = R"(
flat in uint v_group;
flat in uint v_primitive;
#if ROLE_WRITE_ID
layout(location = 0) out uint id;
void main() { id = v_group + 1u; }
#elif ROLE_OTHER_DEPTH
layout(binding = 0) uniform usampler2D id_buffer;
void main() {
  if (texelFetch(id_buffer, ivec2(gl_FragCoord.xy), 0).r == v_group + 1u) discard;
}
#elif ROLE_FLAG
// The depth test (GEQUAL against a nearest-depth buffer) runs before this shader, in the same
// fixed-function quantized arithmetic an occlusion query uses; only passing fragments get here.
layout(early_fragment_tests) in;
layout(binding = 0) uniform usampler2D id_buffer;
layout(std430, binding = 2) buffer Flags { uint flags[]; };
uniform bool against_nearest;  // depth buffer holds the nearest depth (true) or the second (false)
void main() {
  uint owner = texelFetch(id_buffer, ivec2(gl_FragCoord.xy), 0).r;
  bool other = against_nearest ? (owner != 0u && owner != v_group + 1u) : (owner == v_group + 1u);
  if (other) flags[v_primitive] = 1u;
}
#else
void main() {}
#endif
)";

std::string Defines(Shape shape, FragmentRole role) {
  std::string s = "#version 450 core\n";
  s += shape == Shape::kBox ? "#define SHAPE_BOX 1\n" : "#define SHAPE_BOX 0\n";
  s += shape == Shape::kPrism ? "#define SHAPE_PRISM 1\n" : "#define SHAPE_PRISM 0\n";
  s += "#define ROLE_WRITE_ID " + std::to_string(role == FragmentRole::kWriteId) + "\n";
  s += "#define ROLE_OTHER_DEPTH " + std::to_string(role == FragmentRole::kOtherDepth) + "\n";
  s += "#define ROLE_FLAG " + std::to_string(role == FragmentRole::kFlag) + "\n";
  return s;
}

}  // namespace

Shape ShapeOf(PieceSet set) {
  switch (set) {
    case PieceSet::kUobb:
    case PieceSet::kEdgeBoxes:
    case PieceSet::kProxyBoxes:
      return Shape::kBox;
    case PieceSet::kPrisms:
      return Shape::kPrism;
    case PieceSet::kTriangles:
      return Shape::kTriangle;
  }
  return Shape::kTriangle;
}

// Triangle corners of one instance, as indices into its distinct corners (8 for a box, 6 for
// a prism, 3 for a triangle). Indexed draws let the vertex cache shade each distinct corner
// once: llvmpipe runs vertex shaders on one thread, so this is most of a view's vertex cost.
std::span<const uint8_t> CornerIndices(Shape shape) {
  static constexpr std::array<uint8_t, 3> kTriangle = {0, 1, 2};
  if (shape == Shape::kBox) return kBoxTriangleCorners;
  if (shape == Shape::kPrism) return kPrismTriangleCorners;
  return kTriangle;
}

std::string ShaderSource(Shape shape, FragmentRole role, bool vertex) {
  return Defines(shape, role) + (vertex ? kVertexShader : kFragmentShader);
}

}  // namespace far::internal
