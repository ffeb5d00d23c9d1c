#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/result.h"
#include "far/base/step_control.h"
#include "far/model/step_request.h"
#include "far/offsets/bounding_offset.h"

namespace far::internal {

/// The ways an object can be drawn. Each has its own persistent GPU buffer of instances.
enum class PieceSet {
  kUobb,       ///< 1 box per triangle: its rectangle, grown by r in the vertex shader (FAR)
  kEdgeBoxes,  ///< 3 boxes per triangle, one per edge (FAR bounded exact offset)
  kPrisms,     ///< 1 prism per triangle: the triangle shifted by +-r n (FAR bounded exact offset)
  kTriangles,  ///< the triangle itself, unfattened (CULLIDE)
  /// A few axis-aligned boxes (in frame A) that together hold every triangle of the object: a
  /// coarse, conservative stand-in for the whole object at the object level. Drawn grown by
  /// radius_scale r with radius_scale = sqrt(3), since a triangle's UOBB grown by r lies within
  /// its box grown by sqrt(3) r on every axis.
  kProxyBoxes,
};
constexpr int kNumPieceSets = 5;

/// One GPU instance, in the frame A of its object's anchor (object frame shifted to the
/// middle of the object, so that float32 coordinates stay small). 56 bytes.
struct PieceInstance {
  /// kUobb/kEdgeBoxes: center, unit axis u, unit axis v, half extents (u, v, n) before growth.
  /// kPrisms: corners a, b, c and the unit normal n. kTriangles: corners a, b, c, unused.
  std::array<std::array<float, 3>, 4> p;
  uint32_t triangle = 0;  ///< triangle index in the object's mesh
  uint32_t slot = 0;      ///< the object's slot in the renderer
};
static_assert(sizeof(PieceInstance) == 56);

/// GL_RENDERER of the context current on this thread, or "" when none is current.
std::string CurrentGlRenderer();

/// Instances per triangle of each set.
int InstancesPerTriangle(PieceSet set);

/// A kProxyBoxes instance: the axis-aligned box of `center` and `half_extent` (frame A).
PieceInstance ProxyBoxPiece(uint32_t slot, const Eigen::Vector3d& center,
                            const Eigen::Vector3d& half_extent);

/// Builds the instances of one triangle (corners given in frame A) for `set`.
void AppendPieces(PieceSet set, uint32_t slot, uint32_t triangle, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  std::vector<PieceInstance>* out);

/// An object taking part in one axis view.
struct ViewObject {
  uint32_t slot = 0;   ///< where its instances are
  uint32_t group = 0;  ///< self-exclusion unit: primitives of one group never cull each other
  uint32_t first_primitive = 0;  ///< primitive index of its first sub-object
  uint32_t num_triangles = 0;
  Eigen::Isometry3d X_WA = Eigen::Isometry3d::Identity();  ///< anchor frame A in world
  double local_extent = 0;  ///< max |coordinate| of its instances in frame A
};

/// Bound on the float32 rounding of `object`'s pieces as the GPU draws them in a view of
/// `projection`, in world units: the renderer grows every offset by it on top of r. It scales
/// with the object's extent and its distance from the view's center (16 ulps of their sum),
/// not with the view, so a small view of a big object must be grown to hold it (GpuCuller).
double FloatRoundingBound(const ViewObject& object, const Projection& projection);

/// One orthographic view along `axis` of the objects, in the given draw order.
struct AxisView {
  int axis = 2;  ///< view direction: 0 = X (screen Y,Z), 1 = Y (screen Z,X), 2 = Z (screen X,Y)
  Projection projection;
  std::span<const ViewObject> objects;
  int triangles_per_primitive = 0;  ///< sub-object size k; 0 = one primitive per object
  int num_primitives = 0;
  std::span<const uint8_t> alive;  ///< per primitive: 1 if still in the PCS
  std::span<const PieceSet> sets;  ///< what to draw for each triangle
  /// The offsets are drawn grown by radius_scale (r + rounding bound): 1 for the triangles'
  /// own offsets, sqrt(3) for kProxyBoxes.
  double radius_scale = 1.0;
};

/// Counters of the GPU work a view did.
struct RenderCounters {
  int64_t draws = 0;
  int64_t queries = 0;
  int64_t instances = 0;       ///< piece instances submitted
  int64_t bytes_uploaded = 0;  ///< piece and per-object data sent to the GPU
  int64_t pauses = 0;          ///< pauses between batches of draws (BetweenBatches calls)
  /// Where the view's time went: the CPU preparing it (uploads, draw commands), the CPU in its
  /// passes (issuing them, then waiting for and reading back the result), and the GPU's own
  /// time for the passes (a GL_TIME_ELAPSED query). passes_ms well above gpu_ms means the
  /// driver and the round trip cost more than the rendering.
  double prepare_ms = 0;
  double passes_ms = 0;
  double gpu_ms = 0;
};

/// What a long view does between two batches of its draws, with the GL work drawn so far
/// finished: hand the GL lock to other threads' views (far::GlLock::Yield), check the step's
/// deadline and cancellation. Returns kNone to go on, or why the view must stop.
using BetweenBatches = std::function<StopReason()>;

/// Whether a pause between two batches would do anything now: the step can stop (a deadline, a
/// cancel flag), or another thread waits for the GL lock. A pause finishes the GL work drawn so
/// far, which cost paper-leaves' ID-buffer view about a fifth of its time on llvmpipe when
/// nothing needed it (bench/RESULTS.md, "GL views pause only when something needs it").
using PauseWanted = std::function<bool()>;

/// One view's answer: per primitive, 1 if it is not fully visible against the other groups
/// (it stays in the PCS) and 0 if it is (pruned); dead primitives get 0. Empty when the view
/// stopped early (`stopped` says why): a view stopped half-way has no answer.
struct ViewResult {
  std::vector<uint8_t> stays;
  StopReason stopped = StopReason::kNone;
};

/// The GL side of culling: persistent piece buffers (src/piece_buffers.h) and the two
/// visibility mechanisms, one file each (src/id_buffer_culler.cc, src/occlusion_query_culler.cc).
/// Owned by the GL thread (see GlContext's threading contract).
class CullingRenderer {
 public:
  /// Creates framebuffers of `raster`'s size and format and compiles the shaders.
  /// @pre a GL 4.5 context is current. Errors: kInternal (shader or framebuffer failure).
  static Result<std::unique_ptr<CullingRenderer>> Create(const RasterFormat& raster);
  ~CullingRenderer();
  CullingRenderer(const CullingRenderer&) = delete;
  CullingRenderer& operator=(const CullingRenderer&) = delete;

  const RasterFormat& raster() const { return raster_; }
  /// The GL work one batch of a view's draws aims at (RenderView), ms; <= 0: one instance per
  /// batch (for tests). Default 8.
  void set_batch_ms(double batch_ms) { batch_ms_ = batch_ms; }

  /// Replaces the instances of `slot` in `set` (uploaded on the next view that draws `set`).
  void SetPieces(PieceSet set, uint32_t slot, std::vector<PieceInstance> pieces);
  /// Drops `slot` from every set.
  void RemoveSlot(uint32_t slot);

  /// Renders one axis view. Its draws go in batches of a few milliseconds of GL work each
  /// (src/draw_pacer.h); between two batches, when the view has taken that long since the last
  /// pause, its work is finished (glFinish) and `between` runs (may be empty): when that says
  /// stop, the view ends there with no answer (ViewResult::stopped). A view that takes less is
  /// drawn with one call per pass and no pause. With `wanted` (may be empty: always), a batch
  /// boundary pauses only when it says so, and the batches grow fourfold meanwhile.
  Result<ViewResult> RenderView(const AxisView& view, QueryMechanism mechanism,
                                RenderCounters* counters, const BetweenBatches& between = {},
                                const PauseWanted& wanted = {});

 private:
  struct Impl;
  explicit CullingRenderer(std::unique_ptr<Impl> impl, const RasterFormat& raster);
  std::unique_ptr<Impl> impl_;
  RasterFormat raster_;
  double batch_ms_ = 8;
};

}  // namespace far::internal
