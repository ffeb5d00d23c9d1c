#pragma once

// What far-client's replay and the tests need of a Client beyond its public interface. Never
// installed: only the far_client_internal target (tools/far-client, tests) sees this folder.

#include <cstdint>
#include <functional>
#include <string_view>

#include "far/client/client.h"
#include "far/protocol/ring_records.h"

namespace far::client::internal {

/// Replay writes recorded ring records into a session's update ring bit for bit (the public
/// calls normalize poses, which may change the last bit of a recorded quaternion).
struct ClientAccess {
  /// Runs `write` on the session's update ring, as the update calls do: under the client's
  /// update lock (other threads' updates wait), and what it wrote is part of the next step.
  /// Errors: kUnavailable when the session is closed, else those `write` returns.
  static Result<void> WriteUpdates(
      Client& client, const std::function<Result<void>(protocol::UpdateWriter&)>& write);
};

/// An LCM message of a session as the loss seam sees it: one the client is about to publish,
/// or one it has just received and opened (it passed the seal and the sequence check).
struct Datagram {
  bool outgoing = false;   ///< true: client -> daemon
  int64_t session_id = 0;  ///< the session it belongs to
  /// Outgoing: "probe" or "request" (a step's, first or again). Incoming: "status" (state in
  /// `state`, "heard" for a probe's answer), "reply" (a step_reply_t, inline or a stub) or
  /// "error" (an error_t).
  std::string_view kind;
  int64_t step_id = -1;  ///< the step it is about (-1: a probe, or an error_t)
  std::string_view state;
};

/// Test seam: every client of this process asks `lose` about each message before it publishes
/// it or acts on it, and drops it (as LCM over UDP would have lost it) when it returns true.
/// Tests use it to lose requests, statuses and replies on purpose; {} (the default) loses
/// nothing. Thread-safe; `lose` is called on the client's threads.
void SetDatagramLoss(std::function<bool(const Datagram&)> lose);

}  // namespace far::client::internal
