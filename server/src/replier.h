#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "daemon_stats.h"
#include "session.h"

#include "far/model/result.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/session_auth.h"

namespace far::server {

/// Everything the daemon publishes on LCM goes through here, so that every error is counted
/// once and logged once. Thread-safe (LcmBus::Publish is).
class Replier {
 public:
  Replier(protocol::LcmBus& bus, DaemonStats& stats) : bus_(bus), stats_(stats) {}

  /// Publishes bytes; a failure is logged, not returned (nobody to tell).
  void Publish(const std::string& channel, std::span<const uint8_t> bytes);

  /// An error_t on session `session_id`'s reply channel, counted under its code. Signed with
  /// `key` when given, so that the session's client trusts it; unsigned for senders we cannot
  /// authenticate.
  void SessionError(int64_t session_id, const protocol::SessionKey* key, int64_t request_id,
                    const Error& error, bool session_closed);

  /// A failed step's reply (the client waits for a step_reply_t with its step id), counted.
  void StepError(Session& session, int64_t step_id, const Error& error);

  /// A message dropped before it reached a session: counted once (DaemonStats::CountRejected)
  /// and logged. With `reply_session` > 0 an error_t also goes to that session's reply channel,
  /// signed with `key` when the sender was authenticated (a replay), else unsigned.
  void Reject(std::string_view channel, const Error& error, int64_t reply_session = 0,
              int64_t request_id = -1, bool session_closed = false,
              const protocol::SessionKey* key = nullptr);

 private:
  void PublishErrorMessage(int64_t session_id, const protocol::SessionKey* key, int64_t request_id,
                           const Error& error, bool session_closed);

  protocol::LcmBus& bus_;
  DaemonStats& stats_;
};

}  // namespace far::server
