#pragma once

// Building far_lcm messages from far's types and back: step requests (client), step replies
// and error messages (daemon), and the checked conversion of a step reply (client).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "far/base/result.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"
#include "far/protocol/message.h"

namespace far::protocol {

/// Status codes on the wire: 0 is ok, far::ErrorCode values are 1 + their enumerator index
/// (1 invalid_argument, 2 parse_error, 3 io_error, 4 not_found, 5 limit_exceeded,
/// 6 unavailable, 7 busy, 8 permission_denied, 9 timeout, 10 version_mismatch, 11 internal).
inline constexpr int32_t kWireOk = 0;
int32_t ToWireStatus(ErrorCode code);
/// Returns the ErrorCode of a non-zero wire status; unknown values map to kInternal.
ErrorCode FromWireStatus(int32_t status);

/// Builds a step request (auth zero: sign it with EncodeSigned); `timeout_ms` is how long the
/// client will wait for the reply (0: the daemon's deadline).
far_lcm::step_request_t MakeStepRequest(int64_t session_id, int64_t request_id, int64_t step_id,
                                        uint64_t ring_commit_sequence, const StepRequest& request,
                                        int32_t timeout_ms = 0);

/// A probe: a step_request_t whose output is "probe" runs nothing; the daemon answers it at
/// once with a step_status_t in state "heard" (kHeardState). A client sends one right after
/// the open to learn that the daemon hears its LCM messages and that it hears the daemon's
/// (docs/protocol.md, "Lost datagrams and a daemon that cannot hear").
inline constexpr std::string_view kProbeOutput = "probe";
inline constexpr std::string_view kHeardState = "heard";
/// A probe's step id. A daemon older than probes (protocol 3 before issue 41) answers a probe
/// with an error step reply of this step id (output "probe" is not an output it knows): it
/// heard too, and a client takes that answer as "heard".
inline constexpr int64_t kProbeStepId = -1;

/// Builds a probe request (auth zero: sign it with EncodeSigned); its step_id is kProbeStepId.
far_lcm::step_request_t MakeProbeRequest(int64_t session_id, int64_t request_id);
/// True when `message` is a probe (its output is kProbeOutput).
bool IsProbe(const far_lcm::step_request_t& message);

/// The identifiers a step reply echoes.
struct StepReplyIds {
  int64_t session_id = 0;
  int64_t request_id = 0;
  int64_t step_id = 0;
  uint64_t ring_applied_sequence = 0;  ///< last update ring record applied
};

/// Builds the full reply of a successful step (auth zero). Object ids travel as int64, triangle
/// indices as int32 (a valid mesh's always fit). Errors: kLimitExceeded when a count exceeds
/// INT32_MAX or the encoding would exceed kMaxStepReplyBytes; kInternal when a triangle index
/// is over INT32_MAX.
Result<far_lcm::step_reply_t> MakeStepReply(const StepReplyIds& ids, Output output,
                                            const StepResult& result);

/// Builds the reply of a failed step: status and message from `error`, every array empty.
far_lcm::step_reply_t MakeStepErrorReply(const StepReplyIds& ids, const Error& error);

/// Builds a step_status_t (auth zero: it travels sealed); stage "-" when none.
far_lcm::step_status_t MakeStepStatus(int64_t session_id, int64_t request_id, int64_t step_id,
                                      std::string_view state, int32_t queue_position,
                                      std::optional<Stage> stage, double elapsed_ms);

/// Builds an error_t (auth zero).
far_lcm::error_t MakeErrorMessage(int64_t session_id, int64_t request_id, const Error& error,
                                  bool session_closed);

/// Client side: turns a (full, not a stub) step reply into a StepResult. When status != 0,
/// returns the Error it carries (code from FromWireStatus, the daemon's message). Errors:
/// kParseError for inconsistent arrays (object ids outside [0, 2^32-1], negative indices,
/// counts that do not add up), naming the field; kInvalidArgument when called with a stub.
Result<StepResult> ParseStepReply(const far_lcm::step_reply_t& reply);

}  // namespace far::protocol
