#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "far/base/result.h"
#include "far/model/step_request.h"

namespace far::server {

/// A session's estimate of what its next step costs, from what its last step cost: when a step
/// ran into the daemon's step deadline, the same request on a scene at least as large would run
/// into it again, so it is refused at once (kLimitExceeded) instead of holding the session's
/// worker and CPU until the deadline (issue 10: a step's cost is judged before it runs, against
/// the session's budget). The estimate is measured, not modelled: its only input is how the
/// last step of that request ended. The scene may get cheaper without getting smaller (objects
/// move apart), so after `recheck_after` one such step runs again to measure anew. Not
/// thread-safe (the session's worker thread).
class DeadlineMemory {
 public:
  using Clock = std::chrono::steady_clock;
  explicit DeadlineMemory(std::chrono::milliseconds recheck_after)
      : recheck_after_(recheck_after) {}

  /// An error when a step of `request` on `triangles` triangles would run into the deadline as
  /// the last one did; {} to run it.
  Result<void> Check(const StepRequest& request, int64_t triangles, Clock::time_point now) const;

  /// How a step of `request` on `triangles` triangles ended: ran into the daemon's deadline
  /// (`why`: the step's error message), or not (then a remembered step of the same request is
  /// forgotten: this one shows it fits now).
  void Record(const StepRequest& request, int64_t triangles, bool hit_deadline,
              const std::string& why, Clock::time_point now);

 private:
  struct Hit {
    StepRequest request;
    int64_t triangles = 0;
    std::string why;
    Clock::time_point at;
  };
  std::chrono::milliseconds recheck_after_;
  std::optional<Hit> last_;
};

}  // namespace far::server
