#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "far/base/result.h"
#include "far/base/step_control.h"
#include "far/gpu/compute_batcher.h"
#include "far/gpu/gl_context.h"
#include "far/model/mesh.h"
#include "far/model/scene.h"
#include "far/model/scene_model.h"
#include "far/model/scene_update.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"
#include "far/pipeline/gpu_cost.h"
#include "far/pipeline/scene_counters.h"

namespace far {

/// How a Pipeline is made.
struct PipelineOptions {
  GlPlatform platform = GlPlatform::kAuto;
  int gpu_device = -1;  ///< EGL device index to use (GlContext::Create); -1: by `platform`
  int num_threads = 0;  ///< CPU pool for exact tests (0: hardware concurrency)
  /// The cores this pipeline may use (0: all); auto's costs are measured under it. The pool
  /// has CpuPoolThreads(num_threads, cpu_cores) threads.
  int cpu_cores = 0;
  bool use_gl = true;  ///< false: only the CPU methods (aabb, fcl, exact) are available
  /// Use the GL context already current on this thread (owned by the caller, who keeps it
  /// current and alive while the pipeline lives) instead of making one: how a daemon serves
  /// many scenes from one context.
  bool use_current_context = false;
  /// Budgets of the scene (a daemon session's); updates that would exceed them are refused.
  SceneLimits scene_limits;
  /// A budget shared with other pipelines (a daemon's sessions), or null; must outlive this.
  SharedSceneBudget* shared_budget = nullptr;
  /// This scene's holder in `shared_budget` (a daemon session's id, admitted there already).
  int64_t budget_holder = 0;
  /// The GL work one batch of a GPU view's draws aims at, ms. Between two batches of a view
  /// that runs longer, the step's control is checked and the GL lock (far/gpu/gl_lock.h) goes to
  /// the threads waiting for it, so that a view stops within about a batch of its deadline and
  /// other pipelines' views wait about a batch. <= 0: one piece per batch (tests).
  double gl_batch_ms = 8;
  /// The gpu method's GPU work goes to this batcher's thread and context, with other pipelines'
  /// (a daemon's sessions: ComputeBatcher), instead of running on this pipeline's context under
  /// the GL lock; null: on this pipeline's context. Not owned; must outlive the pipeline.
  ComputeBatcher* compute_batcher = nullptr;
};

/// The threads of a pipeline's CPU pool: the smaller of `num_threads` and `cpu_cores` where
/// each is > 0; the machine's cores (std::thread::hardware_concurrency(), at least 1) where
/// neither is.
int CpuPoolThreads(int num_threads, int cpu_cores);

/// The FAR step pipeline: one scene, its GPU resources and a CPU pool. One call runs one step.
///
/// Threading: a Pipeline owns a GL context current on the thread that created it; every call
/// must come from that thread (see GlContext).
class Pipeline {
 public:
  /// Makes the GL context (when use_gl and not use_current_context) and the pool; renderers
  /// are made on first use. Errors: kUnavailable when no GL context can be made (the message
  /// lists what was tried).
  static Result<std::unique_ptr<Pipeline>> Create(const PipelineOptions& options = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Applies a batch of updates in order, all or nothing: every update is checked by the scene
  /// model (far/model/scene_model.h: ids alive, static objects never move, vertices only for
  /// deformable objects, valid meshes and poses, the scene limits) before any is applied.
  /// Errors: the model's (kInvalidArgument, kNotFound, kLimitExceeded), prefixed with
  /// `where(i)` for the i-th update (default "update <i> (<kind>) "); nothing changed.
  Result<void> Apply(std::vector<SceneUpdate> updates,
                     const std::function<std::string(size_t)>& where = {});
  /// One update at a time (errors as Apply, without the prefix).
  Result<void> AddObject(uint32_t id, Mesh mesh, Motion motion, const Pose& X_WO = {});
  Result<void> RemoveObject(uint32_t id);
  Result<void> SetPose(uint32_t id, const Pose& X_WO);
  Result<void> SetVertices(uint32_t id, std::vector<Eigen::Vector3d> p_MV);
  /// Adds every object of `scene` (frames are the caller's to apply).
  Result<void> LoadScene(const Scene& scene);

  /// Runs one step. `control` may stop it (checked at each stage and inside the long ones):
  /// kUnavailable when its cancel flag was set, kTimeout at its deadline, kLimitExceeded when the
  /// answer would hold more than its max_pairs contact and distance pairs; the scene is as the
  /// updates left it either way. Other errors: kInvalidArgument (bad request: resolution,
  /// sub-object size, distance, output needs a distance), kLimitExceeded ('exact' on a scene of
  /// more than kMaxBruteForcePairs triangle pairs), kUnavailable (GPU method without GL),
  /// kInternal.
  Result<StepResult> Step(const StepRequest& request, const StepControl& control = {});

  /// Makes the pipeline's CPU pool background work on at most `max_threads` threads (see
  /// ThreadPool::SetBackground; one way).
  void SetCpuBackground(int max_threads);
  /// The cores this pipeline's steps can count on now (a daemon: its cores over the sessions
  /// stepping; 0, the default: its pool's threads). auto weighs each configuration's CPU time
  /// by it: a step costs at least its CPU time over the share, so where the cores are shared,
  /// a configuration that needs little CPU (gpu) wins over one that needs many cores (bvh).
  /// The pool's loops use at most the share's whole cores (at least one thread:
  /// ThreadPool::SetShare), so that sessions stepping together do not wake more threads than
  /// there are cores for them.
  void SetCpuShare(double cores);
  /// The threads of the CPU pool's parallel loops (the calling thread included).
  int cpu_threads() const;

  int num_objects() const;
  int64_t num_triangles() const;
  const SceneCounters& counters() const;
  /// GL_RENDERER, or "none" without GL.
  std::string gl_renderer() const;

 private:
  struct Impl;
  explicit Pipeline(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Measures what a FAR step and a gpu step cost on the renderer of the GL context current on
/// this thread (the cost model `auto` predicts GPU steps from: measured once per process and
/// renderer, then cached). A daemon calls it at start-up so that no client's first auto step
/// pays for it (seconds on a software rasterizer). nullopt when no context is current or the
/// probe failed.
std::optional<GpuCost> MeasureGpuCost();

/// Makes `cost` this process's cost for the current context's renderer, as if MeasureGpuCost
/// had measured it: a daemon's cost kept from an earlier start (server/src/gpu_cost_cache.h).
/// False when no context is current.
bool UseGpuCost(const GpuCost& cost);

}  // namespace far
