#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "scene_cache.h"
#include <Eigen/Geometry>

#include "far/base/result.h"
#include "far/base/step_control.h"
#include "far/base/thread_pool.h"
#include "far/gpu/compute_batcher.h"
#include "far/gpu/compute_collider.h"
#include "far/model/contact_pair.h"
#include "far/pairs/triangle_bvh.h"

namespace far::internal {

/// The gpu method's GPU stage on the pipeline's side: each object's hierarchy topology, built
/// once on the CPU from its vertices when it first takes part (a deformable object's is then
/// refit, on the GPU, and rebuilt when refitting has made it loose), and what changed since the
/// last step, handed to far::ComputeCollider. Its first step holds the collider to the exact
/// predicates on this driver (SelfCheckComputeCollider, once per renderer and process): a driver
/// that fails it gets kUnavailable for every gpu step (auto then runs bvh). With a
/// far::ComputeBatcher the collider lives on the batcher's thread and context, and each step goes
/// to the GPU in a batch with other pipelines' steps; without one, on the pipeline's own context.
/// Owned by the GL thread (far::GlContext's contract).
class ComputeStage {
 public:
  /// `batcher`: null, or where the collider lives (must outlive this stage).
  ComputeStage(ThreadPool& pool, ComputeBatcher* batcher) : pool_(pool), batcher_(batcher) {}
  ~ComputeStage();
  ComputeStage(const ComputeStage&) = delete;
  ComputeStage& operator=(const ComputeStage&) = delete;

  /// Finds the object pairs on the GPU, as sweep-and-prune at `object_margin` would, and
  /// filters their triangle pairs (ComputeCollider::Run): `objects` by slot (null: free), world
  /// vertices and boxes up to date; `slack` as ComputeQuery's. `distance`: a distance query's D
  /// (ComputeQuery::distance and max_distance); none: a contact query.
  /// The topologies built for new objects are setup (`control`'s on_setup_begin/end); their
  /// builds poll `control` (stopped: returns the stop's reason in `*stopped`, no answer).
  Result<ComputeAnswer> Filter(std::span<const CachedObject* const> objects, double object_margin,
                               double slack, std::optional<double> distance,
                               const StepControl& control, StopReason* stopped);

  /// How many deformable objects' topologies the last Filter rebuilt (they had grown loose).
  int topologies_rebuilt() const { return topologies_rebuilt_; }

  /// Forgets a removed object (its slot may hold another one next).
  void RemoveSlot(ObjectSlot slot);

 private:
  struct SlotState {
    std::vector<ComputeNode> nodes;
    std::vector<uint32_t> order;
    uint64_t topology_key = 0;
    // What p_WV was computed from when last handed over, and the key given to it then.
    uint64_t geometry_stamp = 0;
    Eigen::Matrix<double, 3, 4> X_WM = Eigen::Matrix<double, 3, 4>::Zero();
    uint64_t world_key = 0;
    // A deformable object's hierarchy on the CPU, refit now and then to tell when its topology
    // has grown loose (RebuildLooseTopologies); empty for the others. `deformations` counts
    // the steps whose geometry_stamp was new.
    TriangleBvh shape;
    uint32_t deformations = 0;
  };
  StopReason BuildTopologies(std::span<const CachedObject* const> objects,
                             const StepControl& control);
  StopReason RebuildLooseTopologies(std::span<const CachedObject* const> objects,
                                    const StepControl& control);

  // Makes the collider (here or on the batcher's thread) and checks the driver, once.
  Result<void> MakeCollider(const StepControl& control);
  Result<ComputeAnswer> Run(const ComputeQuery& query);

  ThreadPool& pool_;
  ComputeBatcher* batcher_;
  std::vector<std::optional<SlotState>> slots_;
  // Made on the first step: on this thread's context, or the batcher's collider `batched_id_`.
  std::unique_ptr<ComputeCollider> collider_;
  std::optional<ComputeBatcher::ColliderId> batched_id_;
  Result<void> trusted_;  // the driver's self-check (compute_self_check.h)
  uint64_t next_key_ = 1;
  int topologies_rebuilt_ = 0;
};

}  // namespace far::internal
