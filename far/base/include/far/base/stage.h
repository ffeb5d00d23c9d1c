#pragma once

// The stages of a step (MuJoCo's mjtTimer): one enum, one name each. The names are what the wire
// carries (step replies' stage times, step_status_t), what the stage timers, far-study and
// far-client print, and what StepControl::on_stage reports.

#include <array>
#include <optional>
#include <string_view>

namespace far {

/// A stage of a step, in the order a step runs them (docs/culling.md: the pipeline).
enum class Stage {
  kUpdate,         ///< the world refreshed from the updates: world vertices and boxes
  kObjectCull,     ///< object-level culling (GPU methods) -> object PCS
  kSweepAndPrune,  ///< sweep-and-prune on the objects' boxes -> candidate object pairs
  kPrimitiveCull,  ///< sub-object culling -> primitive PCS
  kExact,          ///< exact triangle tests -> contacts and distance pairs
  kGeometry,       ///< contact points, closest points, penetration (only when asked)
};

/// Every stage, in order.
inline constexpr std::array<Stage, 6> kStages = {Stage::kUpdate,         Stage::kObjectCull,
                                                 Stage::kSweepAndPrune,  Stage::kPrimitiveCull,
                                                 Stage::kExact,          Stage::kGeometry};

/// The stage's name: "update", "object_cull", "sweep_and_prune", "primitive_cull", "exact",
/// "geometry".
constexpr std::string_view ToString(Stage stage) {
  switch (stage) {
    case Stage::kUpdate:
      return "update";
    case Stage::kObjectCull:
      return "object_cull";
    case Stage::kSweepAndPrune:
      return "sweep_and_prune";
    case Stage::kPrimitiveCull:
      return "primitive_cull";
    case Stage::kExact:
      return "exact";
    case Stage::kGeometry:
      return "geometry";
  }
  return "unknown";
}

/// The stage named `name` (ToString's inverse), or nullopt.
constexpr std::optional<Stage> ParseStage(std::string_view name) {
  for (Stage stage : kStages) {
    if (ToString(stage) == name) return stage;
  }
  return std::nullopt;
}

}  // namespace far
