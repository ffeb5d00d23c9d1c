#include "far/pipeline/internal/auto_selector.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace far::internal {
namespace {

std::string Ms(double ms) {
  char text[32];
  std::snprintf(text, sizeof(text), ms < 10 ? "%.2f ms" : "%.0f ms", ms);
  return text;
}

// The candidates, in the order they are tried: the CPU hierarchy first, the GPU step in compute
// shaders, then the raster configurations from the one expected fastest.
std::vector<Candidate> AllCandidates(bool has_gpu) {
  std::vector<Candidate> candidates = {{Method::kBvh, QueryMechanism::kIdBuffer, 0}};
  if (!has_gpu) return candidates;
  candidates.push_back({Method::kGpu, QueryMechanism::kIdBuffer, 0});
  for (int resolution : {256, 1024}) {
    for (QueryMechanism mechanism : {QueryMechanism::kIdBuffer, QueryMechanism::kOcclusionQuery})
      candidates.push_back({Method::kFar, mechanism, resolution});
  }
  candidates.push_back({Method::kFarExactOffset, QueryMechanism::kIdBuffer, 256});
  return candidates;
}

// "; not tried (predicted over 3x the best): A, B 1205 ms; C 600 ms": the candidates skipped
// as hopeless, those with the same prediction named together.
template <typename Entry>
std::string NotTried(const std::vector<const Entry*>& skipped) {
  if (skipped.empty()) return "";
  char factor[16];
  std::snprintf(factor, sizeof(factor), "%g", AutoSelector::kTryFactor);
  std::string text = std::string("; not tried (predicted over ") + factor + "x the best): ";
  for (size_t i = 0; i < skipped.size(); ++i) {
    const std::string ms = Ms(*skipped[i]->predicted_ms);
    text += skipped[i]->candidate.Name();
    const bool last_of_group = i + 1 == skipped.size() || Ms(*skipped[i + 1]->predicted_ms) != ms;
    text += last_of_group ? " " + ms + (i + 1 < skipped.size() ? "; " : "") : ", ";
  }
  return text;
}

std::string Cores(double cores) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f", cores);
  return text;
}

bool Changed(int64_t now, int64_t then, double fraction) {
  return std::abs(static_cast<double>(now - then)) >
         fraction * static_cast<double>(std::max<int64_t>(then, 1));
}

}  // namespace

std::string Candidate::Name() const {
  std::string name(ToString(method));
  if (gpu()) name += "/" + std::string(ToString(mechanism)) + "/" + std::to_string(resolution);
  return name;
}

AutoSelector::AutoSelector(bool has_gpu, std::function<std::optional<GpuCost>()> gpu_cost,
                           int cpu_threads)
    : has_gpu_(has_gpu), cpu_threads_(cpu_threads), probe_gpu_(std::move(gpu_cost)) {}

void AutoSelector::Calibrate(const SceneSize& scene) {
  if (entries_.empty()) {
    for (const Candidate& candidate : AllCandidates(has_gpu_)) {
      entries_.push_back({candidate, {}, {}, {}, {}});
    }
  }
  for (Entry& entry : entries_) {  // which structure each ran on stays known
    entry.measured_ms.reset();
    entry.first_ms.reset();
    entry.predicted_ms.reset();
  }
  if (has_gpu_ && !probed_) {
    gpu_cost_ = probe_gpu_();
    probed_ = true;
  }
  for (Entry& entry : entries_) {
    if (entry.candidate.gpu() && gpu_cost_)
      entry.predicted_ms = gpu_cost_->Predict(scene.triangles);
    if (entry.candidate.method == Method::kGpu) {
      if (gpu_cost_) entry.predicted_ms = gpu_cost_->PredictCompute(scene.triangles);
      if (!entry.predicted_ms) entry.excluded = true;  // its probe did not run: no compute
    }
  }
  calibrated_for_ = scene;
  calibrated_ = true;
  steps_since_calibration_ = 0;
  chosen_calibration_ms_ = 0;
}

AutoSelector::Recheck AutoSelector::NeedsRecheck(const SceneSize& scene) const {
  if (Changed(scene.objects, calibrated_for_.objects, kRecheckChange) ||
      Changed(scene.triangles, calibrated_for_.triangles, kRecheckChange)) {
    return Recheck::kScene;
  }
  // The chosen one got much slower than when it was chosen (and not just by noise on a tiny
  // time): its rivals may have become faster.
  const Entry* chosen = Fastest();
  if (chosen != nullptr && chosen_calibration_ms_ > 0 && *chosen->measured_ms > 1.0 &&
      *chosen->measured_ms > kRecheckDrift * chosen_calibration_ms_) {
    return Recheck::kDrift;
  }
  return steps_since_calibration_ >= recheck_every_ ? Recheck::kPeriodic : Recheck::kNone;
}

const AutoSelector::Entry* AutoSelector::Fastest() const {
  const Entry* best = nullptr;
  for (const Entry& entry : entries_) {
    if (entry.measured_ms && !entry.excluded &&
        (best == nullptr || *entry.measured_ms < *best->measured_ms))
      best = &entry;
  }
  return best;
}

Candidate AutoSelector::Choose(const SceneSize& scene, std::string* reason) {
  structure_ = scene.structure;
  const Recheck recheck = calibrated_ ? NeedsRecheck(scene) : Recheck::kScene;
  if (recheck != Recheck::kNone) {
    // A periodic recheck that keeps the choice waits twice as long for the next; any other
    // recheck, or one that changes the choice, starts the intervals again.
    const Entry* chosen = calibrated_ ? Fastest() : nullptr;
    kept_.reset();
    std::optional<double> kept_ms;
    if (recheck == Recheck::kPeriodic && chosen != nullptr) {
      kept_ = chosen->candidate;
      kept_ms = chosen->measured_ms;
      recheck_every_ = std::min(2 * recheck_every_, kRecheckSteps);
    } else {
      recheck_every_ = FirstRecheck();
    }
    Calibrate(scene);
    // A periodic recheck tries the others against the chosen one's moving average, which says
    // more than one step of it would.
    for (Entry& entry : entries_) {
      if (kept_ && entry.candidate == *kept_) entry.measured_ms = kept_ms;
    }
  }
  const Entry* best = Fastest();
  std::vector<const Entry*> skipped;
  // The next untried candidate that may be fastest.
  for (Entry& entry : entries_) {
    if (entry.measured_ms || entry.excluded) continue;
    const bool hopeless = best != nullptr && entry.predicted_ms &&
                          *entry.predicted_ms > kTryFactor * *best->measured_ms;
    if (hopeless) {
      skipped.push_back(&entry);
      continue;
    }
    const std::string trying =
        entry.first_ms
            ? entry.candidate.Name() + " again (its first run on these objects took " +
                  Ms(*entry.first_ms) + ", one-off work included)"
            : "trying " + entry.candidate.Name() +
                  (entry.predicted_ms ? " (predicted " + Ms(*entry.predicted_ms) + ")" : "");
    trying_ = true;
    *reason =
        "auto: calibrating: " + trying +
        (best ? "; best so far " + best->candidate.Name() + " " + Ms(*best->measured_ms) : "");
    return entry.candidate;
  }
  trying_ = false;
  if (chosen_calibration_ms_ == 0) {  // the calibration's outcome
    chosen_calibration_ms_ = *best->measured_ms;
    if (kept_ && !(*kept_ == best->candidate)) recheck_every_ = FirstRecheck();
    kept_.reset();
  }
  *reason = "auto: " + best->candidate.Name() + " is the fastest measured (" +
            Ms(*best->measured_ms) +
            (cpu_threads_ > 0 ? ", CPU stages on " + std::to_string(cpu_threads_) + " threads"
                              : std::string()) +
            (cpu_share_ > 0 && cpu_share_ < cpu_threads_
                 ? ", CPU time over a " + Cores(cpu_share_) + "-core share"
                 : std::string()) +
            ")";
  for (const Entry& entry : entries_) {
    if (&entry != best && entry.measured_ms)
      *reason += "; " + entry.candidate.Name() + " measured " + Ms(*entry.measured_ms);
  }
  *reason += NotTried(skipped);
  return best->candidate;
}

void AutoSelector::Exclude(const Candidate& candidate) {
  for (Entry& entry : entries_) {
    if (entry.candidate == candidate) entry.excluded = true;
  }
}

void AutoSelector::Record(const Candidate& candidate, double wall_ms, double cpu_ms) {
  ++steps_since_calibration_;
  // The step's cost: its wall time, or its CPU time over the share where that is larger.
  const double ms = cpu_share_ > 0 ? std::max(wall_ms, cpu_ms / cpu_share_) : wall_ms;
  bool steady = false;  // a time without one-off work in it
  for (Entry& entry : entries_) {
    if (!(entry.candidate == candidate)) continue;
    const bool first_on_structure = entry.ran_on != structure_;
    entry.ran_on = structure_;
    if (entry.measured_ms) {
      // A moving average for the one that keeps running, without its first steps on new
      // objects (their one-off work is no step's steady cost).
      if (!first_on_structure) entry.measured_ms = 0.8 * *entry.measured_ms + 0.2 * ms;
    } else if (first_on_structure && !entry.first_ms) {
      entry.first_ms = ms;  // it runs again before it counts
    } else {
      // The faster of its two runs (also when objects change at every step: never a third).
      entry.measured_ms = entry.first_ms ? std::min(*entry.first_ms, ms) : ms;
      steady = true;
    }
  }
  // A GPU candidate that ran tells more about the other GPU ones than the probe did: they are
  // predicted at half its time (resolution and mechanism change it by a factor, not by 10).
  if (candidate.gpu() && steady) {
    for (Entry& entry : entries_) {
      if (entry.candidate.gpu() && !entry.measured_ms) entry.predicted_ms = 0.5 * ms;
    }
  }
}

}  // namespace far::internal
