#pragma once

#include <memory>

#include "compute_stage.h"
#include "fcl_collider.h"
#include "geometry_stage.h"
#include "gpu_culler.h"
#include "scene_cache.h"

#include "far/base/result.h"
#include "far/base/step_control.h"
#include "far/base/thread_pool.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"
#include "far/pairs/sweep_and_prune.h"

namespace far::internal {

/// What a pipeline keeps from step to step besides its scene model: the objects by slot and what
/// each stage keeps of them (GPU pieces, sweep-and-prune's sorted endpoints, FCL's models).
/// Thread safety: none (the pipeline's thread).
struct StepWorld {
  /// `pool` runs the stages' parallel work; aliased, must outlive *this. `with_gpu`: a GPU
  /// culler, which needs a GL context current on this thread for its steps, drawing views in
  /// batches of about `gl_batch_ms` (PipelineOptions::gl_batch_ms).
  /// `compute_batcher`: PipelineOptions::compute_batcher.
  StepWorld(ThreadPool& pool, bool with_gpu, double gl_batch_ms = 8,
            ComputeBatcher* compute_batcher = nullptr);

  /// Applies one update the scene model has accepted; an object removed takes what the stages
  /// keep of it along (its slot and id may come back).
  void Apply(SceneUpdate update);

  ThreadPool& pool;
  SceneCache cache;
  std::unique_ptr<GpuCuller> gpu;         // only with GL
  std::unique_ptr<ComputeStage> compute;  // only with GL
  SweepAndPrune sap;
  FclCollider fcl;
  ClosednessCache closedness;  // the geometry stage's
};

/// Runs one step of a concrete method (not auto) on `world`, each stage only if the request's
/// output needs it: the stages speak slots, and ids come back once, where the result is filled.
/// @pre CheckStepRequest(request) passed, request.method is not kAuto, and GPU methods have
/// world.gpu. Errors: as Pipeline::Step.
Result<StepResult> RunStep(StepWorld& world, const StepRequest& request,
                           const StepControl& control);

}  // namespace far::internal
