#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "daemon_stats.h"
#include "session.h"

#include "far/base/result.h"
#include "far/base/stage.h"
#include "far/protocol/lcm_bus.h"

namespace far::server {

/// Everything the daemon publishes on LCM goes through here: every message for a session is
/// sealed with its key (only its client can read it), and every error is counted once. The
/// answer to each step (reply or error) is kept in the session's ledger before it is sent, so
/// that a repeated request gets it again (Again). Thread-safe (LcmBus::Publish is; a session's
/// messages are sealed and published under its publish_mutex, the ledger under its mutex).
class Replier {
 public:
  /// `status_after`: how old a step must be before StepStatus says where it is
  /// (DaemonConfig::status_after_ms; 0: always).
  Replier(protocol::LcmBus& bus, DaemonStats& stats,
          std::chrono::milliseconds status_after = std::chrono::milliseconds(0))
      : bus_(bus), stats_(stats), status_after_(status_after) {}

  /// Seals an encoded session message (step_reply_t, step_status_t, error_t) for `session`
  /// and publishes it on its reply channel.
  void Seal(Session& session, std::span<const uint8_t> inner);
  /// A step's reply (inline or through the reply ring), kept. Errors: those of
  /// EncodeStepReplyInner (nothing was published; answer with StepError).
  Result<void> StepReply(Session& session, const far_lcm::step_reply_t& full);
  /// A failed step's reply (the client waits for a step_reply_t with its step id), kept and
  /// counted.
  void StepError(Session& session, const protocol::StepCommand& command, const Error& error);
  /// Where a step is: "started", or "stage" (with the stage); nothing while the step is
  /// younger than status_after. Each status is a datagram to every LCM instance on the URL:
  /// a step answered within a few milliseconds is said by its reply alone.
  void StepStatus(Session& session, const StepJob& job, std::string_view state,
                  std::optional<Stage> stage);
  /// "queued" with the step's place: at once when it waits behind another step of the session
  /// (`behind_another`), else as StepStatus.
  void QueuedStatus(Session& session, const StepJob& job, int32_t queue_position,
                    bool behind_another);
  /// The answer to a step asked for again (request `request_id`): its kept reply sealed anew,
  /// where it is (a status), or, when its answer is no longer kept, an error reply (not_found)
  /// that is not kept. The step never runs again.
  void Again(Session& session, int64_t request_id, int64_t step_id, const StepRecall& recall);
  /// The answer to a probe: a step_status_t in state "heard".
  void Heard(Session& session, int64_t request_id);
  /// An error_t for the session (an authenticated message that cannot be answered otherwise,
  /// or the end of the session), counted.
  void SessionError(Session& session, int64_t request_id, const Error& error, bool session_closed);

 private:
  // A failure is logged as the session's user's (LogForClient).
  void Publish(uid_t uid, const std::string& channel, std::span<const uint8_t> bytes);
  // Keeps `inner` as the answer to `step_id`, then seals and publishes it.
  void Answer(Session& session, int64_t step_id, std::vector<uint8_t> inner);
  void Status(Session& session, int64_t request_id, int64_t step_id, std::string_view state,
              int32_t queue_position, std::optional<Stage> stage, Clock::time_point received);

  protocol::LcmBus& bus_;
  DaemonStats& stats_;
  std::chrono::milliseconds status_after_;
};

}  // namespace far::server
