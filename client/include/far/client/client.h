#pragma once

#include <chrono>
#include <cstdint>
#include <future>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "far/model/mesh.h"
#include "far/model/result.h"
#include "far/model/scene.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"

namespace far::client {

/// The daemon's default LCM URL: host-local multicast with a 2 MiB receive buffer (the same as
/// far::protocol::kDefaultLcmUrl, docs/protocol.md; checked at compile time in client.cc).
inline constexpr std::string_view kDefaultLcmUrl =
    "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";

/// How to reach the daemon and what to ask of it.
struct ClientOptions {
  std::string lcm_url = std::string(kDefaultLcmUrl);
  std::string client_name = "far-client";   ///< shown in the daemon's status and logs
  std::chrono::milliseconds timeout{3000};  ///< for opening a session and for Step
  bool heartbeat = true;  ///< send heartbeats from a background thread (else call Heartbeat)
};

/// The daemon's status, as far-client status prints it.
struct DaemonStatus {
  std::string daemon_version, gl_renderer;
  int64_t uptime_ms = 0, steps_total = 0, errors_total = 0, rejected_messages_total = 0;
  int max_sessions = 0;
  double latency_p50_ms = 0, latency_p90_ms = 0, latency_p99_ms = 0, latency_max_ms = 0;
  int64_t latency_samples = 0;
  struct Session {
    int64_t id = 0;
    std::string client_name;
    int64_t steps = 0;
    int objects = 0;
    double latency_p50_ms = 0, latency_p99_ms = 0;
  };
  std::vector<Session> sessions;
  std::vector<std::pair<std::string, int64_t>> errors_by_kind;
};

/// One session with far-daemon: a shared-memory ring for mesh updates and LCM for control.
/// Updates (AddObject, ...) are written to the ring at once and take effect at the next Step.
///
/// Thread safety: one thread at a time per Client (a background thread of its own receives
/// replies and sends heartbeats). Errors are far::Error: kUnavailable "no far-daemon answered"
/// when none runs, kTimeout when a reply does not come, the daemon's own error otherwise.
class Client {
 public:
  /// Opens a session. Errors: kUnavailable (LCM cannot start, or no daemon answered within
  /// options.timeout), the daemon's refusal (kLimitExceeded when it has too many sessions),
  /// kPermissionDenied/kVersionMismatch when the shared memory cannot be trusted.
  static Result<std::unique_ptr<Client>> Connect(const ClientOptions& options = {});
  /// Closes the session (Close) if still open.
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  /// AddObject and SetPose check X_WO with far::CheckPose (finite; quaternion norm within
  /// kQuaternionTolerance of 1) and send it normalized; a pose beyond the tolerance is
  /// kInvalidArgument at once ("set_pose: object 3: X_WO.rotation_wxyz: not a unit quaternion
  /// (norm 1.7): ...") and nothing is written.
  Result<void> AddObject(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO = {});
  Result<void> RemoveObject(uint32_t id);
  Result<void> SetPose(uint32_t id, const Pose& X_WO);
  Result<void> SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV);
  /// Adds every object of a scene.
  Result<void> LoadScene(const Scene& scene);
  /// Applies one animation frame: removals, additions, poses, vertices.
  Result<void> ApplyFrame(const FrameUpdate& frame);

  /// Runs one step of this session's scene and waits for its reply (options.timeout).
  Result<StepResult> Step(const StepRequest& request);
  /// Sends a step and returns at once; the future holds the reply or the error.
  std::future<Result<StepResult>> StepAsync(const StepRequest& request);

  /// Sends a heartbeat (the background thread does this when options.heartbeat).
  Result<void> Heartbeat();
  /// Ends the session; later calls fail with kUnavailable.
  Result<void> Close();

  int64_t session_id() const;
  const std::string& shm_name() const;

  /// Asks the daemon for its status. Errors: kUnavailable when no daemon answered in time.
  static Result<DaemonStatus> Status(const std::string& lcm_url, std::chrono::milliseconds timeout);

 private:
  struct Impl;
  explicit Client(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::client
