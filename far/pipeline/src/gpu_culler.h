#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "scene_cache.h"
#include <Eigen/Geometry>

#include "far/base/result.h"
#include "far/base/step_control.h"
#include "far/gpu/culling_renderer.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"

namespace far::internal {

/// The GPU stages of a step (FAR, FAR with exact offsets, CULLIDE): object-level and
/// sub-object-level culling with three axis views each. Keeps one renderer per raster format,
/// each with the GPU pieces of every object, rebuilt only when the object's vertices change.
/// Owned by the GL thread (see far::GlContext); its GL work runs under far::LockGl, taken per
/// view (the pieces are built and dropped on the CPU, and uploaded in the view that draws them).
/// A long view is drawn in batches: between two, the lock goes to the threads waiting for it
/// (each gets a turn) and the step's control is checked, so a view stops within a batch of
/// its deadline (CullingRenderer::RenderView).
class GpuCuller {
 public:
  /// `counters` gets the piece builds; `pool` builds the pieces of changed objects in
  /// parallel. Both aliased, must outlive *this. `batch_ms`: CullingRenderer::set_batch_ms.
  GpuCuller(SceneCounters& counters, ThreadPool& pool, double batch_ms)
      : counters_(counters), pool_(pool), batch_ms_(batch_ms) {}
  ~GpuCuller();
  GpuCuller(const GpuCuller&) = delete;
  GpuCuller& operator=(const GpuCuller&) = delete;

  /// Culls whole objects: `objects` by slot (null: a free slot); returns, by slot, 1 for the
  /// objects in the object PCS.
  /// @pre the objects' hierarchies are up to date (SceneCache::RefreshHierarchies): the FAR
  /// methods draw a cut of each hierarchy at this level.
  /// The first step of a renderer (its shaders compiled, its pieces built and uploaded) and the
  /// pieces built for objects new to it are setup (`control`'s on_setup_begin/on_setup_end).
  Result<std::vector<uint8_t>> CullObjects(const StepRequest& request,
                                           std::span<const CachedObject* const> objects,
                                           StepStats& stats, const StepControl& control);

  /// Culls sub-objects of k = request.subobject_size triangles of the objects in the slots
  /// `paired`: returns, by slot, the sorted triangles of each object that stay in the primitive
  /// PCS. With `candidates` (by slot, sorted; empty span: every triangle), only the sub-objects
  /// holding a candidate are drawn and only candidates are returned: the triangles the CPU
  /// hierarchy found near a partner.
  Result<std::vector<std::vector<uint32_t>>> CullPrimitives(
      const StepRequest& request, std::span<const CachedObject* const> objects,
      std::span<const ObjectSlot> paired, std::span<const std::vector<uint32_t>> candidates,
      StepStats& stats, const StepControl& control);

  /// Frees a removed object's pieces in every renderer.
  void RemoveSlot(ObjectSlot slot);

 private:
  struct RendererEntry {
    std::unique_ptr<CullingRenderer> renderer;
    std::map<std::pair<uint32_t, int>, uint64_t> built;  // (slot, set) -> geometry stamp
    bool first_step = false;  // the step running now is its first: its GPU stages are setup
  };

  using RendererKeyType = std::tuple<int, int, int>;  // width, height, depth format
  static RendererKeyType RendererKey(const StepRequest& request);
  Result<RendererEntry*> RendererFor(const StepRequest& request);
  StopReason EnsurePieces(RendererEntry& entry, std::span<const CachedObject* const> objects,
                          std::span<const PieceSet> sets, const StepControl& control);
  Result<void> CullLevel(RendererEntry& entry, const StepRequest& request,
                         std::span<const PieceSet> sets, std::span<const ViewObject> view_objects,
                         int k, std::span<const Eigen::AlignedBox3d> primitive_boxes_W,
                         std::vector<uint8_t>& alive, StepStats& stats, LevelCertificate& level,
                         const StepControl& control);

  SceneCounters& counters_;
  ThreadPool& pool_;
  double batch_ms_;
  std::map<RendererKeyType, RendererEntry> renderers_;
};

}  // namespace far::internal
