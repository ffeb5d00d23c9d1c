#pragma once

#include <functional>
#include <span>
#include <string>
#include <string_view>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "replier.h"
#include "session_registry.h"

#include "far/protocol/lcm_bus.h"

namespace far::server {

/// The LCM side of the daemon: step requests on the session channels. Every message is
/// decoded, matched to its session, authenticated and replay-checked before anything else;
/// one that fails is dropped unanswered (counted, logged at a bounded rate): a reply would
/// only help a flood. An authenticated probe is answered "heard"; a request for a step id at
/// or below the session's highest is a repeat, answered from the session's ledger (its kept
/// answer, or where it is) and never run again; both within the session's repeat rate. Other
/// authenticated requests that are invalid or over the session's limits get a sealed error;
/// valid ones are queued for the session's worker. Handlers run on the LCM thread only.
class MessageHandlers {
 public:
  MessageHandlers(const DaemonConfig& config, SessionRegistry& sessions, Replier& replier,
                  DaemonStats& stats);

  /// Subscribes to the daemon's session request channels, each message behind Guarded.
  /// `before_handle`, when set, runs before each handler (a test seam: it may throw).
  void Subscribe(protocol::LcmBus& bus,
                 std::function<void(std::string_view channel)> before_handle = {});

  /// Runs `handler` with the one catch of the daemon's dispatch: an exception is counted as
  /// "internal" and logged in one line; the daemon goes on serving.
  void Guarded(std::string_view channel, std::span<const uint8_t> bytes,
               const protocol::LcmBus::Handler& handler);

  void OnSessionRequest(std::string_view channel, std::span<const uint8_t> bytes);

 private:
  // Takes `step_id` for a new step; false when it is a repeat.
  bool TakeStep(Session& session, int64_t step_id);
  // A probe or a repeated step: answered from what the session keeps, within its repeat rate.
  void AnswerAgain(Session& session, const far_lcm::step_request_t& message);
  void Queue(Session& session, protocol::StepCommand command);

  const DaemonConfig& config_;
  SessionRegistry& sessions_;
  Replier& replier_;
  DaemonStats& stats_;
  const std::string prefix_;
};

}  // namespace far::server
