#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "far/contact_pair.h"
#include "far/gl_context.h"
#include "far/mesh.h"
#include "far/result.h"
#include "far/scene.h"
#include "far/step_request.h"

namespace far {

/// How a Pipeline is made.
struct PipelineOptions {
  GlPlatform platform = GlPlatform::kAuto;
  int num_threads = 0;  ///< CPU pool for exact tests (0: hardware concurrency)
  bool use_gl = true;   ///< false: only the CPU methods (aabb, fcl, exact) are available
  /// Use the GL context already current on this thread (owned by the caller, who keeps it
  /// current and alive while the pipeline lives) instead of making one: how a daemon serves
  /// many scenes from one context.
  bool use_current_context = false;
};

/// Time and work of one stage of a step.
struct StageStats {
  std::string name;  ///< "update", "object_cull", "sweep_and_prune", "primitive_cull", "exact"
  double ms = 0;
};

/// What a step did and cost.
struct StepStats {
  std::vector<StageStats> stages;
  double total_ms = 0;
  int64_t primitives_rendered = 0;  ///< object and sub-object primitives drawn, all views
  int64_t draws = 0;
  int64_t queries = 0;
  int64_t bytes_uploaded = 0;  ///< to the GPU this step
  /// Candidate object pairs after sweep-and-prune. fcl: the pairs its broadphase passed to
  /// collide; exact: the pairs in its answer (it has no candidates).
  int64_t object_pairs = 0;
  /// Candidate triangle pairs (PCS x PCS over object pairs). fcl: n_a * n_b summed over its
  /// broadphase pairs; exact: every cross-object pair.
  int64_t pairs_considered = 0;
  /// Triangle pairs that reached an exact test. fcl: the pairs that reached FCL's own triangle
  /// test, those whose leaf boxes overlapped in its BVH traversal (its num_leaf_tests); exact:
  /// the pairs that passed the triangle-box prefilter.
  int64_t pairs_tested = 0;
  double object_radius = 0;     ///< offset radius r of the last object-level view
  double primitive_radius = 0;  ///< offset radius r of the last sub-object view
};

/// The answer of one step. Ids and triangle indices are as in the scene (docs/scene-format.md).
struct StepResult {
  std::vector<uint32_t> pcs_objects;                         ///< sorted ids
  std::vector<ObjectPair> object_pairs;                      ///< sorted, object_a < object_b
  std::map<uint32_t, std::vector<uint32_t>> pcs_primitives;  ///< id -> sorted triangles
  std::vector<ContactPair> contacts;                         ///< sorted
  std::vector<DistancePair> distance_pairs;                  ///< sorted
  StepStats stats;
};

/// Work the scene bookkeeping did since the pipeline was made: what "only what changed is
/// recomputed or re-uploaded" is tested against.
struct SceneCounters {
  int64_t world_updates = 0;  ///< objects whose world-frame vertices were recomputed
  int64_t piece_builds = 0;   ///< (object, offset kind) GPU piece sets built from vertices
  int64_t piece_bytes = 0;    ///< bytes of piece data handed to the GPU
};

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

  /// Adds an object. Errors (kInvalidArgument): id in use, no triangles, index out of range,
  /// non-finite position or pose.
  Result<void> AddObject(uint32_t id, Mesh mesh, Motion motion, const Pose& X_WO = {});
  /// Removes an object. Errors: kNotFound.
  Result<void> RemoveObject(uint32_t id);
  /// Moves a rigid object. Errors: kNotFound, kInvalidArgument (static object, bad pose).
  Result<void> SetPose(uint32_t id, const Pose& X_WO);
  /// Replaces a deformable object's vertices (same count; triangles unchanged).
  /// Errors: kNotFound, kInvalidArgument (not deformable, wrong count, non-finite).
  Result<void> SetVertices(uint32_t id, std::vector<Eigen::Vector3d> p_MV);
  /// Adds every object of `scene` (frames are the caller's to apply).
  Result<void> LoadScene(const Scene& scene);

  /// Runs one step. Errors: kInvalidArgument (bad request: resolution, sub-object size,
  /// distance, output needs a distance), kUnavailable (GPU method without GL), kInternal.
  Result<StepResult> Step(const StepRequest& request);

  int num_objects() const;
  const SceneCounters& counters() const;
  /// GL_RENDERER, or "none" without GL.
  std::string gl_renderer() const;

 private:
  struct Impl;
  explicit Pipeline(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far
