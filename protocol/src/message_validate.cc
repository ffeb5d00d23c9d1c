#include "far/protocol/message_validate.h"

#include <cmath>
#include <cstdio>

#include "far/protocol/channels.h"
#include "far/protocol/ring_layout.h"

namespace far::protocol {
namespace {

Error Invalid(std::string_view type, std::string_view field, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument,
                   std::string(type) + "." + std::string(field) + ": " + what);
}

// Shows a client string in an error message: quoted, at most 64 characters, non-printable
// bytes escaped (client text must not forge log lines).
std::string Quote(std::string_view text) {
  std::string out = "'";
  for (size_t i = 0; i < text.size() && i < 64; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", c);
      out += escaped;
    }
  }
  if (text.size() > 64) out += "...";
  return out + "'";
}

Result<uint64_t> CheckRingBytes(std::string_view field, int64_t bytes) {
  if (bytes == 0) return uint64_t{0};
  if (bytes < 0 || !IsValidRingCapacity(static_cast<uint64_t>(bytes))) {
    return Invalid("open_session_t", field,
                   std::to_string(bytes) + " is not 0 or a power of two in [" +
                       std::to_string(kMinRingCapacity) + ", " + std::to_string(kMaxRingCapacity) +
                       "]");
  }
  return static_cast<uint64_t>(bytes);
}

}  // namespace

Result<OpenSessionParams> ValidateOpenSession(const far_lcm::open_session_t& message) {
  OpenSessionParams params;
  params.request_id = message.request_id;
  // client_name: shown in status and logs, so printable ASCII only.
  const std::string& name = message.client_name;
  if (name.empty() || name.size() > kMaxClientNameLength) {
    return Invalid("open_session_t", "client_name",
                   "length " + std::to_string(name.size()) + " is outside [1, " +
                       std::to_string(kMaxClientNameLength) + "]");
  }
  for (const char c : name) {
    if (c < 0x20 || c > 0x7e) {
      return Invalid("open_session_t", "client_name",
                     Quote(name) + " has a character that is not printable ASCII");
    }
  }
  params.client_name = name;
  auto update = CheckRingBytes("update_ring_bytes", message.update_ring_bytes);
  if (!update) return update.error();
  auto reply = CheckRingBytes("reply_ring_bytes", message.reply_ring_bytes);
  if (!reply) return reply.error();
  params.update_ring_bytes = *update;
  params.reply_ring_bytes = *reply;
  return params;
}

Result<void> ValidateSessionIds(MessageType type, int64_t session_id, int64_t request_id) {
  if (session_id <= 0) {
    return Invalid(ToString(type), "session_id", std::to_string(session_id) + " is not > 0");
  }
  if (request_id < 0) {
    return Invalid(ToString(type), "request_id", std::to_string(request_id) + " is negative");
  }
  return {};
}

Result<StepCommand> ValidateStepRequest(const far_lcm::step_request_t& message) {
  constexpr std::string_view kType = "step_request_t";
  if (auto ok =
          ValidateSessionIds(MessageType::kStepRequest, message.session_id, message.request_id);
      !ok) {
    return ok.error();
  }
  StepCommand command;
  command.session_id = message.session_id;
  command.request_id = message.request_id;
  if (message.step_id < 0) {
    return Invalid(kType, "step_id", std::to_string(message.step_id) + " is negative");
  }
  command.step_id = message.step_id;
  if (message.ring_commit_sequence < 0) {
    return Invalid(kType, "ring_commit_sequence",
                   std::to_string(message.ring_commit_sequence) + " is negative");
  }
  command.ring_commit_sequence = static_cast<uint64_t>(message.ring_commit_sequence);

  // Names, as on far's command lines.
  StepRequest& request = command.request;
  // No method named: the daemon's default, auto.
  if (message.method.empty()) {
    request.method = Method::kAuto;
  } else if (auto method = ParseMethod(message.method)) {
    request.method = *method;
  } else {
    return Invalid(kType, "method", Quote(message.method) + " is not one of " + MethodNames());
  }
  if (auto mechanism = ParseMechanism(message.mechanism)) {
    request.mechanism = *mechanism;
  } else {
    return Invalid(kType, "mechanism",
                   Quote(message.mechanism) + " is not one of " + MechanismNames());
  }
  if (auto output = ParseOutput(message.output)) {
    request.output = *output;
  } else {
    return Invalid(kType, "output", Quote(message.output) + " is not one of " + OutputNames());
  }
  if (auto format = ParseDepthFormat(message.depth_format)) {
    request.depth_format = *format;
  } else {
    return Invalid(kType, "depth_format",
                   Quote(message.depth_format) + " is not one of " + DepthFormatNames());
  }

  // Ranges and combinations: the model's rule, shared with the pipeline.
  request.resolution = message.resolution;
  request.subobject_size = message.subobject_size;
  if (message.has_distance) {
    request.distance = message.distance;
  } else if (message.distance != 0) {
    // Not fatal for the pipeline, but a client that sets a distance without has_distance has
    // a bug that silently changes its answer: say so.
    return Invalid(kType, "distance",
                   FormatDouble(message.distance) + " is set but has_distance is false");
  }
  request.geometry = message.geometry;
  if (auto ok = CheckStepRequest(request); !ok) {
    return MakeError(ok.error().code, std::string(kType) + "." + ok.error().message);
  }
  if (message.timeout_ms < 0) {
    return Invalid(kType, "timeout_ms", std::to_string(message.timeout_ms) + " is negative");
  }
  command.timeout_ms = message.timeout_ms;
  return command;
}

}  // namespace far::protocol
