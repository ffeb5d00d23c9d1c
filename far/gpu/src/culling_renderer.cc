#include "far/gpu/culling_renderer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "gl_program.h"
#include <epoxy/egl.h>
#include <epoxy/gl.h>

namespace far::internal {
namespace {

// What the fragment shader does in each draw of a view.
enum class FragmentRole {
  kWriteId,     // ID pass 1: nearest front face per pixel, writes its group id
  kOtherDepth,  // ID pass 2: nearest front face of any group other than pass 1's
  kFlag,        // ID pass 3: back faces behind another group's nearest front face flag
  kDepthOnly,   // occlusion queries: depth only
};
constexpr int kNumRoles = 4;

enum class Shape { kBox, kPrism, kTriangle };

Shape ShapeOf(PieceSet set) {
  switch (set) {
    case PieceSet::kUobb:
    case PieceSet::kEdgeBoxes:
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

// glMultiDrawElementsIndirect's command layout.
struct DrawCommand {
  GLuint count;
  GLuint instance_count;
  GLuint first_index;
  GLint base_vertex;
  GLuint base_instance;
};

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

// std430 layout of the shader's ObjectData.
struct ObjectData {
  float M[16];  // column-major
  float radius;
  uint32_t group;
  uint32_t first_primitive;
  uint32_t in_view;
};
static_assert(sizeof(ObjectData) == 80);

GLenum DepthInternalFormat(DepthFormat format) {
  switch (format) {
    case DepthFormat::kDepth16:
      return GL_DEPTH_COMPONENT16;
    case DepthFormat::kDepth24:
      return GL_DEPTH_COMPONENT24;
    case DepthFormat::kDepth32F:
      return GL_DEPTH_COMPONENT32F;
  }
  return GL_DEPTH_COMPONENT24;
}

// Bound on the float32 rounding of one object's corners on the GPU, in world units: the corner
// in frame A (|x| <= local_extent + r), the matrix entries rounded to float (relative 2^-24 on
// rotation and translation), and about ten float operations per corner. 16 ulps covers them
// with room; it is many orders of magnitude below the pixel size in practice.
double FloatRoundingBound(const ViewObject& object, const Projection& projection) {
  const double kUlp = std::ldexp(1.0, -24);
  const double translation = (object.X_WA.translation() - projection.center_W).norm();
  const double half_extent = 0.5 * projection.bounds_W.sizes().maxCoeff();
  return 16.0 * kUlp * (object.local_extent + projection.radius + translation + half_extent);
}

// Builds the object's anchor-to-clip matrix for a view along `axis`: the axis permutation,
// the orthographic scale of the projection bounds, and depth mapped to [0, 1]
// (glClipControl ZERO_TO_ONE). Composed in double, rounded to float once.
void ViewMatrix(int axis, const Projection& projection, const Eigen::Isometry3d& X_WA,
                float out[16]) {
  const Eigen::Vector3d half = 0.5 * projection.bounds_W.sizes();
  const int screen_x = (axis + 1) % 3, screen_y = (axis + 2) % 3;
  Eigen::Matrix4d view = Eigen::Matrix4d::Zero();
  view(0, screen_x) = 1.0 / half[screen_x];
  view(1, screen_y) = 1.0 / half[screen_y];
  view(2, axis) = 0.5 / half[axis];
  view(2, 3) = 0.5;
  view(3, 3) = 1.0;
  Eigen::Matrix4d A_to_local = Eigen::Matrix4d::Identity();
  A_to_local.topLeftCorner<3, 3>() = X_WA.linear();
  A_to_local.topRightCorner<3, 1>() = X_WA.translation() - projection.center_W;
  const Eigen::Matrix4d M = view * A_to_local;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) out[c * 4 + r] = static_cast<float>(M(r, c));
  }
}

std::array<float, 3> ToFloat(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

}  // namespace

std::string CurrentGlRenderer() {
  if (epoxy_egl_version(eglGetCurrentDisplay()) == 0 || eglGetCurrentContext() == EGL_NO_CONTEXT)
    return "";
  const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return name != nullptr ? name : "";
}

int InstancesPerTriangle(PieceSet set) { return set == PieceSet::kEdgeBoxes ? 3 : 1; }

void AppendPieces(PieceSet set, uint32_t slot, uint32_t triangle, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  std::vector<PieceInstance>* out) {
  auto box = [&](const Obb& obb) {
    PieceInstance piece;
    piece.p = {ToFloat(obb.center), ToFloat(obb.axes.col(0)), ToFloat(obb.axes.col(1)),
               ToFloat(obb.half_extents)};
    piece.triangle = triangle;
    piece.slot = slot;
    out->push_back(piece);
  };
  switch (set) {
    case PieceSet::kUobb:
      box(TriangleRectangle(a, b, c));
      break;
    case PieceSet::kEdgeBoxes:
      for (const Obb& edge : ComputeBoundedExactOffset(a, b, c, 0.0).edge_boxes) box(edge);
      break;
    case PieceSet::kPrisms: {
      // The rectangle's third axis is the triangle's unit normal (a valid unit vector even
      // for degenerate triangles, whose prism then lies inside the edge boxes).
      const Eigen::Vector3d n = TriangleRectangle(a, b, c).axes.col(2);
      out->push_back({{ToFloat(a), ToFloat(b), ToFloat(c), ToFloat(n)}, triangle, slot});
      break;
    }
    case PieceSet::kTriangles:
      out->push_back({{ToFloat(a), ToFloat(b), ToFloat(c), {0, 0, 0}}, triangle, slot});
      break;
  }
}

// One set's instances: a CPU copy per slot and one GL buffer with the slots laid out in order.
struct PieceStore {
  std::vector<std::vector<PieceInstance>> slots;
  std::vector<uint64_t> first;  // first instance of each slot in the GL buffer
  std::vector<uint8_t> dirty;
  bool layout_changed = true;
  GLuint buffer = 0, vao = 0;
  uint64_t total = 0;
};

struct CullingRenderer::Impl {
  std::array<PieceStore, kNumPieceSets> stores;
  GLuint programs[3][kNumRoles] = {};  // [shape][role]
  GLuint id_texture = 0, depth_nearest = 0, depth_other = 0;
  GLuint fbo_id = 0, fbo_other = 0, fbo_nearest_only = 0;
  GLuint object_buffer = 0, alive_buffer = 0, flag_buffer = 0;
  std::vector<GLuint> queries;
  GLuint index_buffers[3] = {};                 // per shape: CornerIndices
  GLuint indirect_buffers[kNumPieceSets] = {};  // per set: this view's draw commands
  size_t view_commands[kNumPieceSets] = {};
  uint64_t view_instances[kNumPieceSets] = {};

  ~Impl() {
    for (auto& store : stores) {
      glDeleteBuffers(1, &store.buffer);
      glDeleteVertexArrays(1, &store.vao);
    }
    for (auto& shape : programs) {
      for (GLuint program : shape) glDeleteProgram(program);
    }
    GLuint textures[] = {id_texture, depth_nearest, depth_other};
    glDeleteTextures(3, textures);
    GLuint fbos[] = {fbo_id, fbo_other, fbo_nearest_only};
    glDeleteFramebuffers(3, fbos);
    GLuint buffers[] = {object_buffer, alive_buffer, flag_buffer};
    glDeleteBuffers(3, buffers);
    if (!queries.empty()) glDeleteQueries(static_cast<GLsizei>(queries.size()), queries.data());
    glDeleteBuffers(3, index_buffers);
    glDeleteBuffers(kNumPieceSets, indirect_buffers);
  }

  // Uploads a set's dirty slots: only changed bytes when no slot changed size.
  void Sync(PieceStore& store, RenderCounters* counters) {
    if (store.layout_changed) {
      store.first.assign(store.slots.size(), 0);
      store.total = 0;
      for (size_t s = 0; s < store.slots.size(); ++s) {
        store.first[s] = store.total;
        store.total += store.slots[s].size();
      }
      std::vector<PieceInstance> all;
      all.reserve(store.total);
      for (const auto& slot : store.slots) all.insert(all.end(), slot.begin(), slot.end());
      const auto bytes = static_cast<GLsizeiptr>(all.size() * sizeof(PieceInstance));
      glNamedBufferData(store.buffer, std::max<GLsizeiptr>(bytes, 1), all.data(), GL_STATIC_DRAW);
      counters->bytes_uploaded += bytes;
    } else {
      for (size_t s = 0; s < store.slots.size(); ++s) {
        if (!store.dirty[s] || store.slots[s].empty()) continue;
        const auto bytes = static_cast<GLsizeiptr>(store.slots[s].size() * sizeof(PieceInstance));
        glNamedBufferSubData(store.buffer,
                             static_cast<GLintptr>(store.first[s] * sizeof(PieceInstance)), bytes,
                             store.slots[s].data());
        counters->bytes_uploaded += bytes;
      }
    }
    std::fill(store.dirty.begin(), store.dirty.end(), 0);
    store.layout_changed = false;
  }

  void UseProgram(Shape shape, FragmentRole role, int triangles_per_primitive) {
    GLuint program = programs[static_cast<int>(shape)][static_cast<int>(role)];
    glUseProgram(program);
    glUniform1i(glGetUniformLocation(program, "triangles_per_primitive"), triangles_per_primitive);
  }

  // Draws instances [first, first + count) of a set.
  void Draw(PieceSet set, uint64_t first, uint64_t count, RenderCounters* counters) {
    if (count == 0) return;
    const PieceStore& store = stores[static_cast<int>(set)];
    glBindVertexArray(store.vao);
    glDrawElementsInstancedBaseInstance(
        GL_TRIANGLES, static_cast<GLsizei>(CornerIndices(ShapeOf(set)).size()), GL_UNSIGNED_BYTE,
        nullptr, static_cast<GLsizei>(count), static_cast<GLuint>(first));
    counters->draws++;
    counters->instances += static_cast<int64_t>(count);
  }

  // Prepares one indirect command per object of the view (its instances in `set`), so that a
  // pass draws only the view's objects with one call.
  void PrepareViewDraws(PieceSet set, std::span<const ViewObject> objects, int64_t* bytes) {
    const PieceStore& store = stores[static_cast<int>(set)];
    std::vector<DrawCommand> commands;
    for (const ViewObject& object : objects) {
      if (object.slot >= store.slots.size() || store.slots[object.slot].empty()) continue;
      commands.push_back({static_cast<GLuint>(CornerIndices(ShapeOf(set)).size()),
                          static_cast<GLuint>(store.slots[object.slot].size()), 0, 0,
                          static_cast<GLuint>(store.first[object.slot])});
    }
    view_commands[static_cast<int>(set)] = commands.size();
    view_instances[static_cast<int>(set)] = 0;
    for (const auto& c : commands) view_instances[static_cast<int>(set)] += c.instance_count;
    glNamedBufferData(
        indirect_buffers[static_cast<int>(set)],
        static_cast<GLsizeiptr>(std::max<size_t>(commands.size(), 1) * sizeof(DrawCommand)),
        commands.data(), GL_STREAM_DRAW);
    *bytes += static_cast<int64_t>(commands.size() * sizeof(DrawCommand));
  }

  // Draws every instance of the view's objects in `set` (PrepareViewDraws first).
  void DrawView(PieceSet set, RenderCounters* counters) {
    const int s = static_cast<int>(set);
    if (view_commands[s] == 0) return;
    glBindVertexArray(stores[s].vao);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buffers[s]);
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_BYTE, nullptr,
                                static_cast<GLsizei>(view_commands[s]), 0);
    counters->draws++;
    counters->instances += static_cast<int64_t>(view_instances[s]);
  }
};

CullingRenderer::CullingRenderer(std::unique_ptr<Impl> impl, const RasterFormat& raster)
    : impl_(std::move(impl)), raster_(raster) {}
CullingRenderer::~CullingRenderer() = default;

Result<std::unique_ptr<CullingRenderer>> CullingRenderer::Create(const RasterFormat& raster) {
  if (raster.width < 8 || raster.height < 8 || raster.width > 16384 || raster.height > 16384) {
    return MakeError(ErrorCode::kInvalidArgument, "raster size " + std::to_string(raster.width) +
                                                      "x" + std::to_string(raster.height) +
                                                      " is outside [8, 16384]");
  }
  auto impl = std::make_unique<Impl>();
  // Shaders: one program per piece shape and fragment role.
  for (Shape shape : {Shape::kBox, Shape::kPrism, Shape::kTriangle}) {
    for (int role = 0; role < kNumRoles; ++role) {
      const std::string defines = Defines(shape, static_cast<FragmentRole>(role));
      auto program = LinkProgram(defines + kVertexShader, defines + kFragmentShader);
      if (!program.ok()) return program.error();
      impl->programs[static_cast<int>(shape)][role] = *program;
    }
  }
  // Corner index lists, one per shape.
  for (Shape shape : {Shape::kBox, Shape::kPrism, Shape::kTriangle}) {
    const auto indices = CornerIndices(shape);
    GLuint& buffer = impl->index_buffers[static_cast<int>(shape)];
    glCreateBuffers(1, &buffer);
    glNamedBufferStorage(buffer, static_cast<GLsizeiptr>(indices.size()), indices.data(), 0);
  }
  glCreateBuffers(kNumPieceSets, impl->indirect_buffers);
  // Piece buffers and their vertex layouts (one instance per draw instance).
  for (int set = 0; set < kNumPieceSets; ++set) {
    PieceStore& store = impl->stores[static_cast<size_t>(set)];
    glCreateBuffers(1, &store.buffer);
    glCreateVertexArrays(1, &store.vao);
    glVertexArrayElementBuffer(
        store.vao, impl->index_buffers[static_cast<int>(ShapeOf(static_cast<PieceSet>(set)))]);
    glVertexArrayVertexBuffer(store.vao, 0, store.buffer, 0, sizeof(PieceInstance));
    glVertexArrayBindingDivisor(store.vao, 0, 1);
    for (GLuint i = 0; i < 4; ++i) {
      glEnableVertexArrayAttrib(store.vao, i);
      glVertexArrayAttribFormat(store.vao, i, 3, GL_FLOAT, GL_FALSE, i * 12);
      glVertexArrayAttribBinding(store.vao, i, 0);
    }
    for (GLuint i = 4; i < 6; ++i) {
      glEnableVertexArrayAttrib(store.vao, i);
      glVertexArrayAttribIFormat(store.vao, i, 1, GL_UNSIGNED_INT, 48 + (i - 4) * 4);
      glVertexArrayAttribBinding(store.vao, i, 0);
    }
  }
  // Framebuffers: (id, nearest depth), (other depth), (nearest depth only).
  auto texture = [&](GLenum format) {
    GLuint t = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, format, raster.width, raster.height);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
  };
  impl->id_texture = texture(GL_R32UI);
  impl->depth_nearest = texture(DepthInternalFormat(raster.depth));
  impl->depth_other = texture(DepthInternalFormat(raster.depth));
  glCreateFramebuffers(1, &impl->fbo_id);
  glNamedFramebufferTexture(impl->fbo_id, GL_COLOR_ATTACHMENT0, impl->id_texture, 0);
  glNamedFramebufferTexture(impl->fbo_id, GL_DEPTH_ATTACHMENT, impl->depth_nearest, 0);
  glCreateFramebuffers(1, &impl->fbo_other);
  glNamedFramebufferTexture(impl->fbo_other, GL_DEPTH_ATTACHMENT, impl->depth_other, 0);
  glNamedFramebufferDrawBuffer(impl->fbo_other, GL_NONE);
  glCreateFramebuffers(1, &impl->fbo_nearest_only);
  glNamedFramebufferTexture(impl->fbo_nearest_only, GL_DEPTH_ATTACHMENT, impl->depth_nearest, 0);
  glNamedFramebufferDrawBuffer(impl->fbo_nearest_only, GL_NONE);
  for (GLuint fbo : {impl->fbo_id, impl->fbo_other, impl->fbo_nearest_only}) {
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      return MakeError(ErrorCode::kInternal, "culling framebuffer is incomplete");
    }
  }
  glCreateBuffers(1, &impl->object_buffer);
  glCreateBuffers(1, &impl->alive_buffer);
  glCreateBuffers(1, &impl->flag_buffer);
  // Depth in [0, 1] straight from clip z: the orthographic map is affine, no precision lost.
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  if (auto status = CheckGl("creating the culling renderer"); !status.ok()) return status.error();
  return std::unique_ptr<CullingRenderer>(new CullingRenderer(std::move(impl), raster));
}

void CullingRenderer::SetPieces(PieceSet set, uint32_t slot, std::vector<PieceInstance> pieces) {
  PieceStore& store = impl_->stores[static_cast<int>(set)];
  if (slot >= store.slots.size()) {
    store.slots.resize(slot + 1);
    store.dirty.resize(slot + 1, 0);
    store.layout_changed = true;
  }
  if (store.slots[slot].size() != pieces.size()) store.layout_changed = true;
  store.slots[slot] = std::move(pieces);
  store.dirty[slot] = 1;
}

void CullingRenderer::RemoveSlot(uint32_t slot) {
  for (auto& store : impl_->stores) {
    if (slot < store.slots.size() && !store.slots[slot].empty()) {
      store.slots[slot].clear();
      store.layout_changed = true;
    }
  }
}

bool CullingRenderer::HasPieces(PieceSet set, uint32_t slot) const {
  const PieceStore& store = impl_->stores[static_cast<int>(set)];
  return slot < store.slots.size() && !store.slots[slot].empty();
}

Result<std::vector<uint8_t>> CullingRenderer::RenderView(const AxisView& view,
                                                         QueryMechanism mechanism,
                                                         RenderCounters* counters) {
  Impl& gl = *impl_;
  for (PieceSet set : view.sets) gl.Sync(gl.stores[static_cast<int>(set)], counters);

  // Per-object data for the shaders, indexed by slot; slots outside the view are inactive.
  size_t num_slots = 0;
  for (const auto& store : gl.stores) num_slots = std::max(num_slots, store.slots.size());
  std::vector<ObjectData> objects(std::max<size_t>(num_slots, 1));
  for (auto& o : objects) o = ObjectData{{}, 0.f, 0u, 0u, 0u};
  for (const ViewObject& object : view.objects) {
    ObjectData& o = objects[object.slot];
    ViewMatrix(view.axis, view.projection, object.X_WA, o.M);
    // Unfattened triangles (CULLIDE) get no radius; offsets get r plus their rounding bound.
    const bool fattened = view.sets.empty() || view.sets[0] != PieceSet::kTriangles;
    o.radius = fattened ? static_cast<float>(view.projection.radius +
                                             FloatRoundingBound(object, view.projection))
                        : 0.f;
    o.group = object.group;
    o.first_primitive = object.first_primitive;
    o.in_view = 1;
  }
  std::vector<uint32_t> alive(view.alive.begin(), view.alive.end());
  alive.resize(std::max<size_t>(alive.size(), 1), 0);
  glNamedBufferData(gl.object_buffer, static_cast<GLsizeiptr>(objects.size() * sizeof(ObjectData)),
                    objects.data(), GL_STREAM_DRAW);
  glNamedBufferData(gl.alive_buffer, static_cast<GLsizeiptr>(alive.size() * sizeof(uint32_t)),
                    alive.data(), GL_STREAM_DRAW);
  counters->bytes_uploaded +=
      static_cast<int64_t>(objects.size() * sizeof(ObjectData) + alive.size() * sizeof(uint32_t));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.object_buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.alive_buffer);

  glViewport(0, 0, raster_.width, raster_.height);
  glEnable(GL_DEPTH_TEST);
  // The projection bounds contain every offset grown by r, but each object's float rounding
  // margin (FloatRoundingBound) can reach a hair beyond them. Clamping depth instead of
  // clipping keeps a front fragment in front of, and a back fragment behind, every point of
  // the primitive, which is all Theorem 1 needs; both mechanisms clamp alike.
  glEnable(GL_DEPTH_CLAMP);
  glDisable(GL_BLEND);
  // Orthographic views along the axes are rotations of the world frame (cyclic permutations)
  // followed by a depth axis pointing away from the viewer, which mirrors the image: faces
  // that are counter-clockwise seen from outside appear clockwise when they face the viewer.
  glFrontFace(GL_CW);
  const bool closed = view.sets.empty() || view.sets[0] != PieceSet::kTriangles;
  // Closed offsets: nearest depth from front faces, tests with back faces (the paper's
  // face-culling optimisation). Bare triangles (CULLIDE) have no inside: draw both sides.
  auto cull = [&](GLenum face) {
    if (closed) {
      glEnable(GL_CULL_FACE);
      glCullFace(face);
    } else {
      glDisable(GL_CULL_FACE);
    }
  };
  for (PieceSet set : view.sets) gl.PrepareViewDraws(set, view.objects, &counters->bytes_uploaded);
  auto draw_all = [&](FragmentRole role) {
    for (PieceSet set : view.sets) {
      gl.UseProgram(ShapeOf(set), role, view.triangles_per_primitive);
      gl.DrawView(set, counters);
    }
  };
  // Instance range of sub-object `local` of `object` in `set` (the whole object when k = 0).
  auto primitive_range = [&](const ViewObject& object, PieceSet set, int local) {
    const PieceStore& store = gl.stores[static_cast<int>(set)];
    const uint64_t per = static_cast<uint64_t>(InstancesPerTriangle(set));
    uint64_t first = store.first[object.slot], count = store.slots[object.slot].size();
    if (view.triangles_per_primitive > 0) {
      const uint64_t k = static_cast<uint64_t>(view.triangles_per_primitive);
      const uint64_t begin = static_cast<uint64_t>(local) * k * per;
      count = std::min(count - std::min(count, begin), k * per);
      first += begin;
    }
    return std::make_pair(first, count);
  };
  auto primitives_of = [&](const ViewObject& object) {
    if (view.triangles_per_primitive <= 0) return 1;
    const int k = view.triangles_per_primitive;
    return static_cast<int>((object.num_triangles + static_cast<uint32_t>(k) - 1) /
                            static_cast<uint32_t>(k));
  };

  std::vector<uint8_t> stays(static_cast<size_t>(view.num_primitives), 0);
  if (mechanism == QueryMechanism::kIdBuffer) {
    // Pass 1: nearest front face per pixel and the group it belongs to.
    glBindFramebuffer(GL_FRAMEBUFFER, gl.fbo_id);
    // Depth writes on before clearing: glClearBuffer obeys the depth mask, and the previous
    // view ended with it off (a stale depth buffer would hide primitives).
    glDepthMask(GL_TRUE);
    const GLuint zero_id[4] = {0, 0, 0, 0};
    glClearBufferuiv(GL_COLOR, 0, zero_id);
    const GLfloat far_depth = 1.f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    glDepthFunc(GL_LESS);
    cull(GL_BACK);
    draw_all(FragmentRole::kWriteId);
    // Pass 2: nearest front face of any other group (ties between groups land here).
    glBindFramebuffer(GL_FRAMEBUFFER, gl.fbo_other);
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    glBindTextureUnit(0, gl.id_texture);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    draw_all(FragmentRole::kOtherDepth);
    // Pass 3: back faces at or behind another group's nearest front face flag their primitive.
    std::vector<uint32_t> flags(stays.size() + 1, 0);
    glNamedBufferData(gl.flag_buffer, static_cast<GLsizeiptr>(flags.size() * sizeof(uint32_t)),
                      flags.data(), GL_STREAM_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gl.flag_buffer);
    glDepthMask(GL_FALSE);
    glDepthFunc(GL_GEQUAL);
    cull(GL_FRONT);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    for (bool against_nearest : {true, false}) {
      glBindFramebuffer(GL_FRAMEBUFFER, against_nearest ? gl.fbo_nearest_only : gl.fbo_other);
      for (PieceSet set : view.sets) {
        gl.UseProgram(ShapeOf(set), FragmentRole::kFlag, view.triangles_per_primitive);
        glUniform1i(
            glGetUniformLocation(gl.programs[static_cast<int>(ShapeOf(set))][2], "against_nearest"),
            against_nearest ? 1 : 0);
        gl.DrawView(set, counters);
      }
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(gl.flag_buffer, 0,
                            static_cast<GLsizeiptr>(flags.size() * sizeof(uint32_t)), flags.data());
    for (size_t i = 0; i < stays.size(); ++i) stays[i] = flags[i] != 0 && view.alive[i] != 0;
  } else {
    // The paper's two passes with one occlusion query per primitive: forward order, then
    // reverse order querying only the primitives fully visible in the first pass.
    if (gl.queries.size() < stays.size()) {
      const size_t old = gl.queries.size();
      gl.queries.resize(stays.size());
      glGenQueries(static_cast<GLsizei>(stays.size() - old), gl.queries.data() + old);
    }
    std::vector<uint8_t> visible_forward(stays.size(), 0);
    glBindFramebuffer(GL_FRAMEBUFFER, gl.fbo_nearest_only);
    const GLfloat far_depth = 1.f;
    for (int pass = 0; pass < 2; ++pass) {
      glDepthMask(GL_TRUE);  // glClearBuffer obeys the depth mask
      glClearBufferfv(GL_DEPTH, 0, &far_depth);
      std::vector<uint8_t> queried(stays.size(), 0);
      int since_flush = 0;
      const int n = static_cast<int>(view.objects.size());
      for (int step = 0; step < n; ++step) {
        const ViewObject& object =
            view.objects[static_cast<size_t>(pass == 0 ? step : n - 1 - step)];
        const int num_local = primitives_of(object);
        // Query each live primitive's back faces against the objects drawn so far.
        glDepthMask(GL_FALSE);
        glDepthFunc(GL_GEQUAL);
        cull(GL_FRONT);
        for (int local = 0; local < num_local; ++local) {
          const uint32_t primitive = object.first_primitive + static_cast<uint32_t>(local);
          if (!view.alive[primitive] || (pass == 1 && !visible_forward[primitive])) continue;
          glBeginQuery(GL_SAMPLES_PASSED, gl.queries[primitive]);
          for (PieceSet set : view.sets) {
            gl.UseProgram(ShapeOf(set), FragmentRole::kDepthOnly, view.triangles_per_primitive);
            auto [first, count] = primitive_range(object, set, local);
            gl.Draw(set, first, count, counters);
          }
          glEndQuery(GL_SAMPLES_PASSED);
          queried[primitive] = 1;
          counters->queries++;
          // Mesa 22.3 llvmpipe over-counts some results at 1536^2 and up unless flushed at
          // least every 200 queries (DESIGN.md).
          if (++since_flush == 128) {
            glFlush();
            since_flush = 0;
          }
        }
        // Then draw the object's front faces into the depth buffer.
        glDepthMask(GL_TRUE);
        glDepthFunc(GL_LEQUAL);
        cull(GL_BACK);
        for (PieceSet set : view.sets) {
          gl.UseProgram(ShapeOf(set), FragmentRole::kDepthOnly, view.triangles_per_primitive);
          const PieceStore& store = gl.stores[static_cast<int>(set)];
          gl.Draw(set, store.first[object.slot], store.slots[object.slot].size(), counters);
        }
      }
      // Read the results: zero samples passed means fully visible in this pass.
      for (size_t p = 0; p < stays.size(); ++p) {
        if (!queried[p]) continue;
        GLuint samples = 0;
        glGetQueryObjectuiv(gl.queries[p], GL_QUERY_RESULT, &samples);
        if (pass == 0) {
          visible_forward[p] = samples == 0;
          if (samples != 0) stays[p] = 1;
        } else if (samples != 0) {
          stays[p] = 1;
        }
      }
    }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (auto status = CheckGl("rendering a culling view"); !status.ok()) return status.error();
  return stays;
}

}  // namespace far::internal
