#pragma once
// far-client replay: when a replayed step's reply matches the recorded one
// (docs/record-replay.md, "What matches").
#include <string>
#include <vector>

#include "far/base/result.h"
#include "far/model/step_result.h"

namespace far::cli {

struct CompareOptions {
  /// The replay's daemon has the recording daemon's GL_RENDERER (both known).
  bool same_renderer = false;
  /// --strict: every difference fails, PCS and object pairs included.
  bool strict = false;
};

/// The differences between a recorded and a replayed reply.
struct StepComparison {
  bool compared = true;                 ///< false: the recorded step ended client-side
  std::vector<std::string> mismatches;  ///< differences that fail the replay, first one first
  std::vector<std::string> notes;       ///< differences allowed here (PCS on another renderer)
  std::string summary;                  ///< counts, e.g. "contacts 12, distance pairs 0, ..."
  bool matches() const { return mismatches.empty(); }
};

/// Compares one step. `recorded` is the recorded outcome (a result, or the error a failed step
/// recorded); `replayed` what the replay's daemon answered.
StepComparison CompareStep(const Result<StepResult>& recorded, const Result<StepResult>& replayed,
                           const CompareOptions& options);

}  // namespace far::cli
