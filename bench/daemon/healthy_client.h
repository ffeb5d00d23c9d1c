#pragma once

// The well-behaved client of the hardening study: a ~1K-triangle scene (8 rigid clusters of
// 128 triangles) whose objects move every step, stepped back to back or at a simulator's fixed
// rate (method bvh, contacts), with each step's round trip recorded.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "study_daemon.h"

#include "far/base/result.h"
#include "far/client/client.h"
#include "far/model/scene.h"

namespace far::study {

/// What a client saw over a stretch of time.
struct LatencySample {
  std::vector<double> ms;  ///< round trip of each step that succeeded
  int errors = 0;          ///< steps that failed (timeouts included)
  double seconds = 0;
  std::string first_error;

  double StepsPerSecond() const { return seconds > 0 ? ms.size() / seconds : 0; }
  void Merge(const LatencySample& other);
};

class HealthyClient {
 public:
  /// Opens a session named `name` and uploads the scene. A step that takes longer than
  /// `timeout` counts as an error.
  static Result<std::unique_ptr<HealthyClient>> Open(const StudyDaemon& daemon,
                                                     const std::string& name,
                                                     std::chrono::milliseconds timeout);
  /// Steps for `seconds`: back to back when steps_per_second is 0, else one step every
  /// 1 / steps_per_second seconds as a simulator's clock would (a late step starts at once,
  /// and the clock does not try to catch up).
  LatencySample StepFor(double seconds, double steps_per_second = 0);
  int64_t session_id() const { return client_->session_id(); }

 private:
  HealthyClient() = default;
  bool MoveObjects();
  std::unique_ptr<client::Client> client_;
  std::vector<SceneObject> objects_;
  StepRequest request_;
  int64_t step_ = 0;
};

}  // namespace far::study
