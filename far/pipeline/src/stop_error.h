#pragma once

#include "far/base/result.h"
#include "far/base/stage.h"
#include "far/base/step_control.h"

namespace far::internal {

/// Why a step stopped, as its error, naming the stage it was in: the caller's cancellation
/// (kUnavailable), its deadline (kTimeout, "step stopped at its deadline (during exact)"), the
/// reply's pair cap (kLimitExceeded, naming control.max_pairs). The one wording every stage
/// uses.
Error StopError(StopReason reason, Stage stage, const StepControl& control);

}  // namespace far::internal
