#pragma once

// Meaning checks of decoded client messages (after DecodeMessage and, for session messages,
// VerifyEncoded). Every error names the field and the bad value, e.g.
// "step_request_t.resolution: 5 is outside [8, 8192]". Nothing here trusts the client: the
// results are the only form in which client values reach the rest of the daemon.

#include <cstdint>
#include <string>

#include "far/base/result.h"
#include "far/model/step_request.h"
#include "far/protocol/message.h"

namespace far::protocol {

/// The longest client name (open_session_t.client_name). Step request ranges are the model's
/// (far/base/limits.h, far::CheckStepRequest), shared with far::Pipeline.
inline constexpr size_t kMaxClientNameLength = 64;

/// A checked open_session_t.
struct OpenSessionParams {
  int64_t request_id = 0;
  std::string client_name;         ///< 1..64 printable ASCII characters
  uint64_t update_ring_bytes = 0;  ///< 0 (daemon default) or a valid ring capacity
  uint64_t reply_ring_bytes = 0;   ///< 0 (daemon default) or a valid ring capacity
};

/// Checks an open_session_t. Errors: kInvalidArgument naming the field.
Result<OpenSessionParams> ValidateOpenSession(const far_lcm::open_session_t& message);

/// A checked step_request_t, converted to far's types.
struct StepCommand {
  int64_t session_id = 0;
  int64_t request_id = 0;
  int64_t step_id = 0;
  uint64_t ring_commit_sequence = 0;  ///< drain the update ring up to this record sequence
  int32_t timeout_ms = 0;             ///< how long the client waits (0: the daemon's deadline)
  StepRequest request;
};

/// Checks a step_request_t: session_id > 0, request_id, step_id, ring_commit_sequence >= 0,
/// known method/mechanism/output/depth_format names (the message lists the known names),
/// distance 0 unless has_distance, then far::CheckStepRequest (ranges and combinations). Errors:
/// kInvalidArgument naming the field.
Result<StepCommand> ValidateStepRequest(const far_lcm::step_request_t& message);

/// Checks the common part of a session message: session_id > 0 and request_id >= 0.
/// Errors: kInvalidArgument naming the field.
Result<void> ValidateSessionIds(MessageType type, int64_t session_id, int64_t request_id);

}  // namespace far::protocol
