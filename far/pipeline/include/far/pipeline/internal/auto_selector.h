#pragma once

// far::internal: visible to the tests, not part of the API.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "far/model/step_request.h"
#include "far/pipeline/gpu_cost.h"

namespace far::internal {

/// A concrete configuration `auto` may run.
struct Candidate {
  Method method = Method::kBvh;
  QueryMechanism mechanism = QueryMechanism::kIdBuffer;
  int resolution = 256;

  /// A raster configuration (FAR): it has a mechanism and a resolution.
  bool gpu() const { return method == Method::kFar || method == Method::kFarExactOffset; }
  /// "bvh", "far/id-buffer/256".
  std::string Name() const;
  bool operator==(const Candidate&) const = default;
};

using far::GpuCost;  // far/pipeline/gpu_cost.h

/// What auto knows of the scene when it chooses: its size, to tell when it changed enough that
/// the costs measured before no longer hold.
struct SceneSize {
  int64_t objects = 0;
  int64_t triangles = 0;
  /// Changes whenever an object is added or removed: a configuration's first step on a new set
  /// of objects does one-off work (builds their hierarchies, uploads their geometry).
  uint64_t structure = 0;
};

/// Chooses, step by step, the fastest reliable configuration for one pipeline's renderer and
/// scene, from costs it measures:
///  - it calibrates on the first steps: each candidate that may be fastest runs and its time
///    is recorded (bvh always first: it is reliable on every host and rarely slow). A run that
///    is the candidate's first on the current set of objects (SceneSize::structure) also did
///    one-off work, hierarchies built or geometry uploaded (bvh's first step on far-client's
///    bunnies scene took 85 ms, its next 15 ms), so the candidate runs once more and the faster of
///    the two runs counts;
///  - with a GPU, the gpu method (compute shaders) is the second candidate, predicted from its
///    own probe (not a candidate when that probe failed); it, too, runs only when its
///    prediction is within kTryFactor of the best;
///  - a GPU candidate runs only when its predicted time (the renderer's fixed cost per step
///    plus its cost per triangle times the scene's triangles, both measured once per process
///    on two fixed probe scenes) is within kTryFactor of the best measured time: on a software
///    rasterizer the GPU methods cost milliseconds per step and tens of microseconds per
///    triangle, so they are not tried where the CPU is clearly faster;
///  - then it runs the fastest measured one, with a moving average of its time that leaves out
///    its first steps on new objects, and re-calibrates when the scene's object or
///    triangle count changed by more than kRecheckChange since, when the chosen one's time has
///    drifted above kRecheckDrift times what it measured, and periodically: kFirstRecheckSteps
///    steps after a calibration, then twice as long after each periodic one that kept the same
///    choice, up to kRecheckSteps. A periodic recheck runs the other candidates once each
///    against the chosen one's moving average. A time measured once can be a transient (a
///    session's step queued behind other sessions' one-off GPU setup, cores busy with a burst):
///    without the early rechecks a candidate that lost to one stays unused for kRecheckSteps
///    steps.
/// Every candidate is reliable: cullide, fcl and exact are never chosen.
/// Thread safety: none (the pipeline's thread).
class AutoSelector {
 public:
  static constexpr double kTryFactor = 3.0;
  static constexpr double kRecheckChange = 0.25;
  static constexpr double kRecheckDrift = 2.0;
  static constexpr int64_t kRecheckSteps = 1000;
  static constexpr int64_t kFirstRecheckSteps = 32;

  /// `gpu_cost` measures (once) the renderer's cost of a FAR step and of a gpu step, or gives
  /// nullopt when it cannot; it is only called when there is a GPU. `cpu_threads`: the threads
  /// the pipeline's CPU stages may use (its cores, PipelineOptions::cpu_cores): every time it
  /// measures is measured under that budget, and its reasons say so (0: not said).
  AutoSelector(bool has_gpu, std::function<std::optional<GpuCost>()> gpu_cost, int cpu_threads = 0);

  /// The configuration for the next step, and why (filled into the step's stats).
  Candidate Choose(const SceneSize& scene, std::string* reason);
  /// Records the time of a step that ran `candidate` (the one Choose just gave): its wall time
  /// and, when known, the CPU time its pipeline used (all threads). Its cost is the larger of
  /// the wall time and the CPU time over the CPU share (set_cpu_share): on cores other
  /// sessions or simulators also need, a step that keeps 16 threads busy costs what they
  /// would take from the others.
  void Record(const Candidate& candidate, double wall_ms, double cpu_ms = 0);
  /// The cores the pipeline can count on now (0: only wall times count).
  void set_cpu_share(double cores) { cpu_share_ = cores; }
  /// Never chooses `candidate` again (its step failed: its GPU resources or limits do not fit
  /// this scene); the next Choose goes on with the others.
  void Exclude(const Candidate& candidate);
  /// Whether the last Choose gave a candidate to try (calibrating), not the chosen one.
  bool trying() const { return trying_; }

 private:
  struct Entry {
    Candidate candidate;
    std::optional<double> measured_ms;   // last measured since the calibration
    std::optional<double> first_ms;      // a first run on the structure, with its one-off work
    std::optional<double> predicted_ms;  // GPU candidates: from the probe
    std::optional<uint64_t> ran_on;      // the structure it last ran on (kept across calibrations)
    bool excluded = false;               // never chosen: no prediction for gpu, or its step failed
  };
  enum class Recheck { kNone, kScene, kDrift, kPeriodic };
  void Calibrate(const SceneSize& scene);
  Recheck NeedsRecheck(const SceneSize& scene) const;
  // Without a GPU bvh is the only candidate: nothing to recheck early.
  int64_t FirstRecheck() const { return has_gpu_ ? kFirstRecheckSteps : kRecheckSteps; }
  const Entry* Fastest() const;

  bool has_gpu_;
  int cpu_threads_ = 0;
  double cpu_share_ = 0;
  std::function<std::optional<GpuCost>()> probe_gpu_;
  std::optional<GpuCost> gpu_cost_;  // once probed
  bool probed_ = false;
  std::vector<Entry> entries_;
  SceneSize calibrated_for_;
  uint64_t structure_ = 0;  // of the scene of the last Choose
  bool calibrated_ = false;
  bool trying_ = false;
  int64_t steps_since_calibration_ = 0;
  int64_t recheck_every_ = kRecheckSteps;  // the periodic recheck's interval now
  std::optional<Candidate> kept_;          // the choice before a periodic recheck, while it runs
  double chosen_calibration_ms_ = 0;
};

}  // namespace far::internal
