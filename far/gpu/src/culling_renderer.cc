#include "far/gpu/culling_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include "draw_pacer.h"
#include "gl_program.h"
#include "gl_timer.h"
#include "piece_buffers.h"
#include "view_pass.h"
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "far/base/limits.h"

namespace far::internal {
namespace {

// std430 layout of the shader's ObjectData.
struct ObjectData {
  float M[16];  // column-major
  float radius;
  uint32_t group;
  uint32_t first_primitive;
  uint32_t in_view;
};
static_assert(sizeof(ObjectData) == 80);

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

// The view's scale for bounding its pieces' fill (the radius comes with the view's data).
ViewScale ScaleOf(const AxisView& view, const RasterFormat& raster) {
  const Eigen::Vector3d size = view.projection.bounds_W.sizes();
  const int screen_x = (view.axis + 1) % 3, screen_y = (view.axis + 2) % 3;
  ViewScale scale;
  scale.px_per_unit = std::max(raster.width / size[screen_x], raster.height / size[screen_y]);
  scale.view_pixels = static_cast<double>(raster.width) * raster.height;
  return scale;
}

std::array<float, 3> ToFloat(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

}  // namespace

// The corner in frame A (|x| <= local_extent + r), the matrix entries rounded to float
// (relative 2^-24 on rotation and translation), and about ten float operations per corner:
// 16 ulps covers them with room.
double FloatRoundingBound(const ViewObject& object, const Projection& projection) {
  const double kUlp = std::ldexp(1.0, -24);
  const double translation = (object.X_WA.translation() - projection.center_W).norm();
  const double half_extent = 0.5 * projection.bounds_W.sizes().maxCoeff();
  return 16.0 * kUlp * (object.local_extent + projection.radius + translation + half_extent);
}

std::string CurrentGlRenderer() {
  if (epoxy_egl_version(eglGetCurrentDisplay()) == 0 || eglGetCurrentContext() == EGL_NO_CONTEXT)
    return "";
  const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return name != nullptr ? name : "";
}

int InstancesPerTriangle(PieceSet set) { return set == PieceSet::kEdgeBoxes ? 3 : 1; }

PieceInstance ProxyBoxPiece(uint32_t slot, const Eigen::Vector3d& center,
                            const Eigen::Vector3d& half_extent) {
  return {{ToFloat(center), {1, 0, 0}, {0, 1, 0}, ToFloat(half_extent)}, 0, slot};
}

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
    case PieceSet::kProxyBoxes:
      break;  // per object, not per triangle (ProxyBoxPiece)
  }
}

struct CullingRenderer::Impl {
  std::unique_ptr<PieceBuffers> pieces;
  std::unique_ptr<CullingPrograms> programs;
  std::unique_ptr<CullTargets> targets;
  GLuint object_buffer = 0, alive_buffer = 0;
  GLuint timer_query = 0;     // GL_TIME_ELAPSED of a view's passes
  GLuint fragment_query = 0;  // a batch's fragment shader invocations (0: not supported)
  BatchCosts batch_costs;     // what a batch of draws costs here, from view to view

  ~Impl() {
    GLuint buffers[] = {object_buffer, alive_buffer};
    glDeleteBuffers(2, buffers);
    glDeleteQueries(1, &timer_query);
    if (fragment_query != 0) glDeleteQueries(1, &fragment_query);
  }

  // Per-object data for the shaders (indexed by slot; slots outside the view are inactive) and
  // the primitives still alive, bound for the vertex shader.
  // Returns the largest radius the view grows an object's pieces by.
  double UploadViewData(const AxisView& view, RenderCounters* counters);
  // The fixed-function state every view starts from.
  void SetViewState(const RasterFormat& raster) const;
};

double CullingRenderer::Impl::UploadViewData(const AxisView& view, RenderCounters* counters) {
  std::vector<ObjectData> objects(std::max<size_t>(pieces->num_slots(), 1),
                                  ObjectData{{}, 0.f, 0u, 0u, 0u});
  // Unfattened triangles (CULLIDE) get no radius; offsets get r plus their rounding bound.
  const bool fattened = view.sets.empty() || view.sets[0] != PieceSet::kTriangles;
  double largest_radius = 0;
  for (const ViewObject& object : view.objects) {
    ObjectData& o = objects[object.slot];
    ViewMatrix(view.axis, view.projection, object.X_WA, o.M);
    o.radius =
        fattened
            ? static_cast<float>(view.radius_scale * (view.projection.radius +
                                                      FloatRoundingBound(object, view.projection)))
            : 0.f;
    largest_radius = std::max(largest_radius, static_cast<double>(o.radius));
    o.group = object.group;
    o.first_primitive = object.first_primitive;
    o.in_view = 1;
  }
  std::vector<uint32_t> alive(view.alive.begin(), view.alive.end());
  alive.resize(std::max<size_t>(alive.size(), 1), 0);
  glNamedBufferData(object_buffer, static_cast<GLsizeiptr>(objects.size() * sizeof(ObjectData)),
                    objects.data(), GL_STREAM_DRAW);
  glNamedBufferData(alive_buffer, static_cast<GLsizeiptr>(alive.size() * sizeof(uint32_t)),
                    alive.data(), GL_STREAM_DRAW);
  counters->bytes_uploaded +=
      static_cast<int64_t>(objects.size() * sizeof(ObjectData) + alive.size() * sizeof(uint32_t));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, object_buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, alive_buffer);
  return largest_radius;
}

void CullingRenderer::Impl::SetViewState(const RasterFormat& raster) const {
  glViewport(0, 0, raster.width, raster.height);
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
}

CullingRenderer::CullingRenderer(std::unique_ptr<Impl> impl, const RasterFormat& raster)
    : impl_(std::move(impl)), raster_(raster) {}
CullingRenderer::~CullingRenderer() = default;

Result<std::unique_ptr<CullingRenderer>> CullingRenderer::Create(const RasterFormat& raster) {
  if (raster.width < kMinResolution || raster.height < kMinResolution ||
      raster.width > kMaxResolution || raster.height > kMaxResolution) {
    return MakeError(ErrorCode::kInvalidArgument, "raster size " + std::to_string(raster.width) +
                                                      "x" + std::to_string(raster.height) +
                                                      " is outside [" +
                                                      std::to_string(kMinResolution) + ", " +
                                                      std::to_string(kMaxResolution) + "]");
  }
  auto impl = std::make_unique<Impl>();
  auto programs = CullingPrograms::Create();
  if (!programs.ok()) return programs.error();
  impl->programs = std::move(*programs);
  auto targets = CullTargets::Create(raster);
  if (!targets.ok()) return targets.error();
  impl->targets = std::move(*targets);
  impl->pieces = std::make_unique<PieceBuffers>();
  glCreateBuffers(1, &impl->object_buffer);
  glCreateBuffers(1, &impl->alive_buffer);
  glCreateQueries(GL_TIME_ELAPSED, 1, &impl->timer_query);
  // Pipeline statistics (core in GL 4.6) let the draw pacer bound a batch's fill (draw_pacer.h).
  // glGenQueries: Mesa 22.3's glCreateQueries refuses their targets (GL_INVALID_ENUM).
  if (epoxy_gl_version() >= 46 || epoxy_has_gl_extension("GL_ARB_pipeline_statistics_query"))
    glGenQueries(1, &impl->fragment_query);
  // Depth in [0, 1] straight from clip z: the orthographic map is affine, no precision lost.
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  if (auto status = CheckGl("creating the culling renderer"); !status.ok()) return status.error();
  return std::unique_ptr<CullingRenderer>(new CullingRenderer(std::move(impl), raster));
}

void CullingRenderer::SetPieces(PieceSet set, uint32_t slot, std::vector<PieceInstance> pieces) {
  impl_->pieces->SetPieces(set, slot, std::move(pieces));
}

void CullingRenderer::RemoveSlot(uint32_t slot) { impl_->pieces->RemoveSlot(slot); }

Result<ViewResult> CullingRenderer::RenderView(const AxisView& view, QueryMechanism mechanism,
                                               RenderCounters* counters,
                                               const BetweenBatches& between,
                                               const PauseWanted& wanted) {
  using Clock = std::chrono::steady_clock;
  const auto ms_since = [](Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  };
  Impl& gl = *impl_;
  // The GPU's time of the passes, without the pauses: the timer stops for each.
  GLuint64 gpu_ns = 0;
  bool timing = false;  // the timer query runs (during the passes)
  Clock::time_point timer_began;
  const auto begin_timer = [&] {
    timer_began = Clock::now();
    glBeginQuery(GL_TIME_ELAPSED, gl.timer_query);
  };
  const auto read_timer = [&] {
    if (!timing) return;
    glEndQuery(GL_TIME_ELAPSED);
    gpu_ns += ElapsedNsOrZero(gl.timer_query, timer_began);
  };
  double paused_ms = 0;
  const BetweenBatches pause = [&] {
    read_timer();
    const Clock::time_point start = Clock::now();
    const StopReason stop = between ? between() : StopReason::kNone;
    paused_ms += ms_since(start);
    if (timing) begin_timer();
    return stop;
  };
  DrawPacer pacer(gl.batch_costs, pause, batch_ms_, wanted,
                  FillBound{ScaleOf(view, raster_), gl.fragment_query});
  // The pieces' uploads (in parts, with pauses), the view's data and draw commands.
  const Clock::time_point prepare_start = Clock::now();
  for (PieceSet set : view.sets) {
    if (!gl.pieces->Sync(set, pacer, counters)) return ViewResult{{}, pacer.stopped()};
  }
  pacer.set_fill_radius(gl.UploadViewData(view, counters));
  gl.SetViewState(raster_);
  for (PieceSet set : view.sets)
    gl.pieces->PrepareViewDraws(set, view.objects, view.alive, view.triangles_per_primitive,
                                &counters->bytes_uploaded);
  counters->prepare_ms += ms_since(prepare_start) - paused_ms;
  const Clock::time_point passes_start = Clock::now();
  paused_ms = 0;
  timing = true;
  begin_timer();
  ViewPass pass(view, *gl.pieces, *gl.programs, pacer, counters);
  std::optional<std::vector<uint8_t>> stays = mechanism == QueryMechanism::kIdBuffer
                                                  ? CullWithIdBuffer(pass, *gl.targets)
                                                  : CullWithOcclusionQueries(pass, *gl.targets);
  // The mechanism read its result back (or finished at its last pause), so the passes are done
  // and the timer's result does not wait on them.
  read_timer();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  counters->passes_ms += ms_since(passes_start) - paused_ms;
  counters->gpu_ms += static_cast<double>(gpu_ns) * 1e-6;
  counters->pauses += pacer.pauses();
  if (auto status = CheckGl("rendering a culling view"); !status.ok()) return status.error();
  if (!stays) return ViewResult{{}, pacer.stopped()};
  return ViewResult{std::move(*stays), StopReason::kNone};
}

}  // namespace far::internal
