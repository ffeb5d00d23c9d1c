#include "stop_error.h"

#include <string>

namespace far::internal {

Error StopError(StopReason reason, Stage stage, const StepControl& control) {
  const std::string where = " (during " + std::string(ToString(stage)) + ")";
  switch (reason) {
    case StopReason::kCancelled:
      return MakeError(ErrorCode::kUnavailable, "step cancelled by its caller" + where);
    case StopReason::kDeadline:
      return MakeError(ErrorCode::kTimeout, "step stopped at its deadline" + where);
    case StopReason::kPairLimit:
      return MakeError(ErrorCode::kLimitExceeded,
                       "the answer has more than " + std::to_string(control.max_pairs) +
                           " contact and distance pairs, the most a reply may carry" + where +
                           ": ask for a smaller distance D, or a shallower output (pcs)");
    case StopReason::kNone:
      break;
  }
  return MakeError(ErrorCode::kInternal, "step stopped for no reason" + where);
}

}  // namespace far::internal
