#include "deadline_memory.h"

#include <algorithm>
#include <cstdio>
#include <tuple>

namespace far::server {
namespace {

// Everything in a request that changes what a step costs.
auto CostKey(const StepRequest& r) {
  return std::make_tuple(r.method, r.mechanism, r.resolution, r.depth_format, r.subobject_size,
                         r.distance, r.output);
}

std::string Seconds(std::chrono::steady_clock::duration d) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", std::chrono::duration<double>(d).count());
  return text;
}

}  // namespace

Result<void> DeadlineMemory::Check(const StepRequest& request, int64_t triangles,
                                   Clock::time_point now) const {
  if (!last_ || CostKey(request) != CostKey(last_->request) || triangles < last_->triangles ||
      now - last_->at >= recheck_after_) {
    return {};
  }
  return MakeError(
      ErrorCode::kLimitExceeded,
      "step refused before it ran: the last step of this request ('" +
          std::string(ToString(request.method)) + "', output '" +
          std::string(ToString(request.output)) + "') on " + std::to_string(last_->triangles) +
          " triangles ran into the daemon's step deadline " + Seconds(now - last_->at) + " ago (" +
          last_->why +
          "), and this scene is no smaller; the updates were applied. "
          "Ask for less (another method, a smaller distance or resolution, fewer triangles), or "
          "the daemon tries this request again " +
          Seconds(recheck_after_) + " after the last one");
}

std::chrono::milliseconds DeadlineMemory::blame_after() const {
  const auto slack = std::max(std::chrono::milliseconds(1000), step_deadline_ / 20);
  return step_deadline_ - slack;
}

void DeadlineMemory::Record(const StepRequest& request, int64_t triangles, const StepEnd& end,
                            Clock::time_point now) {
  if (!end.hit_deadline) {
    if (last_ && CostKey(request) == CostKey(last_->request)) last_.reset();
    return;
  }
  // Stopped at the deadline after waiting for most of it: not shown too heavy.
  if (end.ran < blame_after()) return;
  last_ = Hit{request, triangles, end.why, now};
}

}  // namespace far::server
