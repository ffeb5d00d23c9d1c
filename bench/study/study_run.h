#pragma once

// far-study's configurations and the interleaved run of one scene: every configuration owns a
// far::Pipeline (all on the caller's current GL context), gets the same updates, and all run
// one after the other within each step, in an order that rotates from step to step, so that
// machine noise and cache effects hit all of them alike.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "study_scenes.h"

#include "far/base/result.h"
#include "far/base/stage.h"
#include "far/model/scene_update.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"

namespace far_study {

/// One configuration: what a step request asks for.
struct ConfigSpec {
  far::Method method = far::Method::kBvh;
  std::optional<far::QueryMechanism> mechanism;  ///< GPU methods only
  int resolution = 0;                            ///< GPU methods only
  far::Output output = far::Output::kContacts;   ///< kDistancePairs: the distance pass

  /// As StepStats::method names it: "bvh", "far/id-buffer/256".
  std::string Name() const;
};

/// Parses "far/id-buffer/256" (a GPU method, a mechanism, a resolution); nullopt when malformed.
std::optional<ConfigSpec> ParseGpuConfig(const std::string& text);

/// Which configurations run where (see ConfigsFor).
struct RunOptions {
  std::vector<int> resolutions = {256, 512, 1024, 2048};  ///< small scenes' GPU configurations
  int oq_steps = 0;  ///< occlusion-query configurations on the first N steps only (0: all)
  std::vector<ConfigSpec> paper_gpu;    ///< GPU configurations of the paper-scale scenes
  std::vector<ConfigSpec> scaling_gpu;  ///< ... of the scaling scenes up to scaling_gpu_max
  int64_t scaling_gpu_max = 50000;
  int64_t scaling_reference_max = 300000;
  std::set<std::string> methods;  ///< method names to run (empty: all); the reference always
  bool distance_on_paper = true;  ///< the distance pass on the paper-scale scenes
  bool distance_on_scaling = false;
  /// D of the distance pass, as a fraction of the diagonal of the scene's world box at step 0.
  double distance_fraction = 0.001;
  /// The reference on this many measured steps of each scene, spread evenly (and the scene's
  /// key_steps); 0: on every measured step.
  int reference_steps = 0;

  /// The resolution the small-scene bars compare at: 1024 when run, else the largest.
  int PrimaryResolution() const;
};

/// A stage's place in the arrays of stage times below.
constexpr size_t StageIndex(far::Stage stage) { return static_cast<size_t>(stage); }

/// What one step of one configuration measured.
struct Sample {
  int step = 0;          ///< the measured step, 1..steps
  double step_ms = 0;    ///< ingest + Step, wall clock
  double cpu_ms = 0;     ///< the same span in CPU time of the whole process (llvmpipe's too)
  double ingest_ms = 0;  ///< Pipeline::Apply of the step's updates
  double cull_ms = 0;    ///< object_cull + primitive_cull stages
  std::array<double, far::kStages.size()> stage_ms{};  ///< by StageIndex
  int64_t pcs_objects = 0, pcs_primitives = 0, object_pairs = 0, pairs_considered = 0;
  int64_t pairs_tested = 0, subobject_input = 0, queries = 0, draws = 0, primitives_rendered = 0;
  double gl_prepare_ms = 0, gl_passes_ms = 0, gl_gpu_ms = 0;  ///< StepStats' GL split
  far::GpuFilterCounters gpu_filter;                          ///< the gpu method's filters
  int64_t contacts = 0, reference = 0, missed = 0, false_positives = 0;
  int64_t distance_pairs = 0, distance_reference = 0, distance_missed = 0, distance_spurious = 0;
  bool checked = false;  ///< the reference ran at this step: the four counts above are known
  std::string method_run, method_reason;  ///< StepStats::method and method_reason
};

/// A configuration's samples on one scene, summarized: medians per step, totals over steps.
struct Row {
  ConfigSpec spec;
  std::string config, method, mechanism, output;  ///< config: spec.Name(); mechanism "-" for CPU
  int resolution = 0;
  int samples = 0;
  bool reference = false;  ///< this row is the scene's reference (exact)
  bool checked = false;    ///< some measured step was checked: missed / false positives known
  int checked_steps = 0;   ///< samples checked against the reference (the totals count these)
  double ms_median = 0, ms_p25 = 0, ms_p75 = 0, ms_min = 0, ms_max = 0, cpu_ms = 0;
  std::map<int, double> ms_by_step;  ///< measured step -> its time (one sample per step)
  double ingest_ms = 0, cull_ms = 0;
  std::array<double, far::kStages.size()> stage_ms{};  ///< by StageIndex
  double pcs_objects = 0, pcs_primitives = 0, object_pairs = 0, pairs_considered = 0;
  double pairs_tested = 0, subobject_input = 0, queries = 0, draws = 0, primitives_rendered = 0;
  double gl_prepare_ms = 0, gl_passes_ms = 0, gl_gpu_ms = 0;  ///< medians
  /// gpu: medians of its filters' pairs (boxes met, float-decided, fp64-decided, to the CPU)
  /// and of the GPU time of its refit, traversal and filters.
  double gpu_box_pairs = 0, gpu_float = 0, gpu_double = 0, gpu_cpu = 0, gpu_distance_culled = 0;
  double gpu_refit_ms = 0, gpu_traverse_ms = 0, gpu_filter_ms = 0;
  int64_t contacts = 0, reference_contacts = 0, missed = 0, false_positives = 0;
  int64_t distance_pairs = 0, distance_reference = 0, distance_missed = 0, distance_spurious = 0;
  int64_t object_pairs_total = 0, pairs_considered_total = 0;
  std::map<std::string, int> runs;  ///< StepStats::method -> measured steps it ran
  std::string method_run;           ///< the configuration that ran most often
  std::string method_reason;        ///< auto: the reason of its last measured step

  bool distance() const { return spec.output == far::Output::kDistancePairs; }
};

/// One scene's run: what it was and a row per configuration.
struct SceneReport {
  std::string name, description, break_note;
  int break_step = 0;  ///< breaking: the measured step of the break; 0: none
  Family family = Family::kSmall;
  Kind kind = Kind::kRigid;
  int64_t triangles = 0;
  int objects = 0, steps = 0;
  std::optional<double> distance;    ///< D of the distance pass, when it ran
  bool checked = false;              ///< a reference ran
  std::vector<int> reference_steps;  ///< the measured steps it ran on
  double seconds = 0;
  std::vector<Row> rows;

  /// Which reference checked the rows, on which steps: "the brute force (`exact`) on measured
  /// steps 1, 3, 4, 6 of 6", or that there was none.
  std::string ReferenceText() const;
};

/// The configurations of `scene`, the reference (exact) last, or none when the scene is past
/// scaling_reference_max. Where the distance pass runs, the reference asks for distance pairs
/// (it answers contacts too, so one brute force serves both).
std::vector<ConfigSpec> ConfigsFor(const StudyScene& scene, const RunOptions& options,
                                   bool* has_reference);

/// The measured steps (1..steps) the reference runs on: all when `count` is 0 or at least
/// `steps`; else `count` steps spread evenly, the first and the last included (one: the first),
/// and every key step.
std::vector<int> ReferenceSteps(int steps, int count, const std::vector<int>& key_steps);

/// The order in which the configurations run at step s: (offset + n * stride) mod count for
/// n = 0 .. count - 1, the offset rotating by one per step and the stride cycling through the
/// numbers coprime to count, so that no configuration always follows the same one.
std::vector<size_t> StepOrder(size_t count, int s);

/// Runs every configuration of `scene` over its frames (an unmeasured warm-up step 0, then
/// one measured step per frame). Errors: a pipeline cannot be made, an update or step failed.
far::Result<SceneReport> RunScene(const StudyScene& scene, const RunOptions& options);

/// The row of a configuration ("far/id-buffer/1024") and output; nullptr when not run.
const Row* Find(const SceneReport& report, const std::string& config,
                far::Output output = far::Output::kContacts);

/// Copies of a frame's updates, in the order Pipeline::Apply expects them.
std::vector<far::SceneUpdate> ToUpdates(const far::FrameUpdate& frame);

}  // namespace far_study
