#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "far/base/result.h"
#include "far/model/step_request.h"

namespace far::server {

/// A session's estimate of what its next step costs, from what its last step cost: when a step
/// ran into the daemon's step deadline on its own time, the same request on a scene at least as
/// large would run into it again, so it is refused at once (kLimitExceeded) instead of holding
/// the session's worker and CPU until the deadline (issue 10: a step's cost is judged before it
/// runs, against the session's budget). The estimate is measured, not modelled: its only input
/// is how the last step of that request ended. The scene may get cheaper without getting
/// smaller (objects move apart), so after `recheck_deadlines` deadlines one such step runs again
/// to measure anew.
///
/// Only a step's own running time blames it (issue 41): its time from leaving the session's
/// queue to its end, less the time it waited for other sessions' GL work (far::GlLockWaitedMs).
/// A step that spent more than the deadline's slack (the larger of 1 s and 5% of it) waiting in
/// the queue or behind another session did not show that it is too heavy, and is neither
/// remembered nor forgets a remembered one. Not thread-safe (the session's worker thread).
class DeadlineMemory {
 public:
  using Clock = std::chrono::steady_clock;

  /// How one step ended.
  struct StepEnd {
    bool hit_deadline = false;  ///< it stopped at the daemon's step deadline (not a shorter one)
    std::chrono::milliseconds ran{0};  ///< its own running time (waits excluded, see above)
    std::string why;                   ///< its error message, when it failed
  };

  DeadlineMemory(std::chrono::milliseconds step_deadline, int recheck_deadlines)
      : step_deadline_(step_deadline), recheck_after_(recheck_deadlines * step_deadline) {}

  /// An error when a step of `request` on `triangles` triangles would run into the deadline as
  /// the last one did; {} to run it.
  Result<void> Check(const StepRequest& request, int64_t triangles, Clock::time_point now) const;

  /// How a step of `request` on `triangles` triangles ended: ran into the daemon's deadline on
  /// its own time (remembered), finished (a remembered step of the same request is forgotten:
  /// this one shows it fits now), or neither (nothing changes).
  void Record(const StepRequest& request, int64_t triangles, const StepEnd& end,
              Clock::time_point now);

  /// The own running time from which a step that ran into the deadline is blamed for it: the
  /// deadline less the larger of 1 s and 5% of it.
  std::chrono::milliseconds blame_after() const;

 private:
  struct Hit {
    StepRequest request;
    int64_t triangles = 0;
    std::string why;
    Clock::time_point at;
  };
  std::chrono::milliseconds step_deadline_;
  std::chrono::milliseconds recheck_after_;
  std::optional<Hit> last_;
};

}  // namespace far::server
