#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "daemon_stats.h"
#include "session.h"

#include "far/base/result.h"
#include "far/base/stage.h"
#include "far/protocol/lcm_bus.h"

namespace far::server {

/// Everything the daemon publishes on LCM goes through here: every message for a session is
/// sealed with its key (only its client can read it), and every error is counted once.
/// Thread-safe (LcmBus::Publish is; each session's sequence is atomic).
class Replier {
 public:
  Replier(protocol::LcmBus& bus, DaemonStats& stats) : bus_(bus), stats_(stats) {}

  /// Seals an encoded session message (step_reply_t, step_status_t, error_t) for `session`
  /// and publishes it on its reply channel.
  void Seal(Session& session, std::span<const uint8_t> inner);
  /// A step's reply (inline or through the reply ring). Errors: those of
  /// EncodeStepReplyForTransport (nothing was published; answer with StepError).
  Result<void> StepReply(Session& session, const far_lcm::step_reply_t& full);
  /// A failed step's reply (the client waits for a step_reply_t with its step id), counted.
  void StepError(Session& session, const protocol::StepCommand& command, const Error& error);
  /// Where a step is: "queued" (with its place), "started", or "stage" (with the stage).
  void StepStatus(Session& session, const StepJob& job, std::string_view state,
                  int32_t queue_position, std::optional<Stage> stage);
  /// An error_t for the session (an authenticated message that cannot be answered otherwise,
  /// or the end of the session), counted.
  void SessionError(Session& session, int64_t request_id, const Error& error, bool session_closed);

 private:
  // A failure is logged as the session's user's (LogForClient).
  void Publish(uid_t uid, const std::string& channel, std::span<const uint8_t> bytes);

  protocol::LcmBus& bus_;
  DaemonStats& stats_;
};

}  // namespace far::server
