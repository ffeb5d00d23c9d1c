#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/step_control.h"
#include "far/base/thread_pool.h"
#include "far/model/mesh.h"
#include "far/model/object_slot.h"
#include "far/model/pose.h"
#include "far/model/scene_update.h"
#include "far/pairs/triangle_bvh.h"
#include "far/pairs/world_object.h"
#include "far/pipeline/scene_counters.h"

namespace far::internal {

/// One object of a pipeline's scene and what is derived from it. Vertex-derived data is
/// recomputed only when the vertices change, world data only when the pose or vertices change.
struct CachedObject {
  CachedObject() = default;
  CachedObject(const CachedObject&) = default;
  CachedObject& operator=(const CachedObject&) = default;
  // Moves that cannot throw, said so: Eigen's AlignedBox does not say it, and without this a
  // growing vector of objects (SceneCache::slots_) copied every mesh, vertex and hierarchy it
  // held instead of moving them.
  CachedObject(CachedObject&&) noexcept = default;
  CachedObject& operator=(CachedObject&&) noexcept = default;

  uint32_t id = 0;
  ObjectSlot slot{};  ///< its index in every array of a step (object_slot.h)
  Motion motion = Motion::kStatic;
  Mesh mesh;  ///< frame M
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
  uint64_t geometry_stamp = 0;  ///< changes whenever p_MV changes
  // From p_MV, for the GPU methods only (RefreshGpuGeometry), when gpu_stamp != geometry_stamp:
  uint64_t gpu_stamp = 0;
  Eigen::Vector3d anchor_M = Eigen::Vector3d::Zero();  ///< middle of the mesh: frame A's origin
  double local_extent = 0;                             ///< bound on |x| of pieces in frame A
  std::vector<Eigen::AlignedBox3d> rect_boxes_M;       ///< per triangle, its rectangle's AABB
  Eigen::AlignedBox3d rect_box_M;                      ///< union of rect_boxes_M
  // From p_MV and the pose:
  bool world_dirty = true;
  /// World vertices equal to p_MV (the identity pose, no tiny coordinate to flush): p_WV() is
  /// p_MV itself, so a deformable object's vertices are not copied every step.
  bool world_is_model = false;
  std::vector<Eigen::Vector3d> placed_WV;  ///< the world vertices, unless world_is_model
  Eigen::AlignedBox3d box_W;               ///< AABB of the world vertices
  // The hierarchy of p_MV (the bvh method), built on first use, refit when p_MV changes:
  TriangleBvh bvh;
  uint64_t bvh_stamp = 0;  ///< geometry_stamp the hierarchy was made for (0: never)

  Eigen::Isometry3d X_WA() const { return X_WM * Eigen::Translation3d(anchor_M); }
  /// The world vertices flush(X_WM p_MV) (FlushTinyCoordinates), what every exact test reads.
  /// Valid after RefreshWorld, until the next update of this object.
  std::span<const Eigen::Vector3d> p_WV() const {
    return world_is_model ? std::span<const Eigen::Vector3d>(mesh.p_MV) : placed_WV;
  }
};

/// The objects of a pipeline by slot, kept up to date by updates that the scene model has
/// already accepted. A new object takes the most recently freed slot, else the next one: slots
/// stay dense. Thread safety: none (the pipeline's thread).
class SceneCache {
 public:
  /// Applies one update. @pre far::SceneModel accepted it (ids alive, sizes and poses valid).
  /// Returns the slot an object removal freed (its GPU pieces and FCL model must go).
  std::optional<ObjectSlot> Apply(SceneUpdate update);

  /// Recomputes the world-frame vertices of objects that moved or deformed, an object per
  /// chunk on `pool`.
  void RefreshWorld(ThreadPool& pool);

  /// Every slot's object (null: a free slot), indexed by slot; valid until the next Apply.
  std::vector<const CachedObject*> Objects() const;
  /// Every slot's world view (empty: a free slot), indexed by slot; valid until the next Apply.
  std::vector<WorldObjectView> WorldViews() const;
  /// Every slot's object id (a free slot's is meaningless), indexed by slot: what turns a step's
  /// answers into ids (far/model/slot_ids.h).
  std::span<const uint32_t> ids() const { return ids_; }

  /// Computes the GPU methods' data from the vertices (anchor, piece extent, rectangle boxes)
  /// of the objects whose vertices changed since, on `pool`. Checks `control` every few tens
  /// of thousands of triangles: when it says stop, returns why (the objects done so far keep
  /// their data, the others are done again by the next call), else kNone.
  [[nodiscard]] StopReason RefreshGpuGeometry(ThreadPool& pool, const StepControl& control);
  /// Brings the hierarchies of the objects in `slots` up to date with their vertices on `pool`:
  /// built once for static and rigid objects, refit (rebuilt when loose) for deformed ones.
  /// The builds are the step's setup (`control`'s on_setup_begin and on_setup_end around
  /// them); the refits are per-step work. The builds poll `control` as they go (TriangleBvh::
  /// Build): when it says stop, returns why; the hierarchies finished so far are kept, and an
  /// object whose build was abandoned has none until a later call builds it. Else kNone.
  [[nodiscard]] StopReason RefreshHierarchies(std::span<const ObjectSlot> slots, ThreadPool& pool,
                                              const StepControl& control);

  /// Objects in the scene.
  int size() const { return static_cast<int>(slot_of_id_.size()); }
  /// Slots in use or free: one past the largest slot.
  size_t num_slots() const { return slots_.size(); }
  /// Changes whenever an object is added or removed.
  uint64_t structure() const { return structure_; }
  const SceneCounters& counters() const { return counters_; }
  SceneCounters& counters() { return counters_; }

 private:
  CachedObject& At(uint32_t id) { return *slots_[Index(slot_of_id_.at(id))]; }
  void RefreshGeometry(CachedObject& object);
  // False when `stopper` stopped it (the object's data is then stale: gpu_stamp unchanged).
  static bool ComputeGpuGeometry(CachedObject& object, StepStopper& stopper);

  std::vector<std::optional<CachedObject>> slots_;
  std::vector<uint32_t> ids_;  // by slot
  std::unordered_map<uint32_t, ObjectSlot> slot_of_id_;
  std::vector<ObjectSlot> free_slots_;
  uint64_t next_stamp_ = 1;
  uint64_t structure_ = 0;
  SceneCounters counters_;
};

}  // namespace far::internal
