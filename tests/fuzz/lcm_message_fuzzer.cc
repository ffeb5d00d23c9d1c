// Fuzz target lcm_message: every far_lcm type's guarded decoding (DecodeMessage: cap,
// fingerprint, schema pre-scan, LCM's decode, version) and far's checks of what decoded:
// ValidateOpenSession, ValidateStepRequest, ValidateSessionIds (daemon side) and
// ParseStepReply (client side). The input is one encoded message, as a datagram or a local
// socket message carries it.
//
// Oracles besides the sanitizers: a payload that decodes as T is identified as T and
// re-encodes to exactly the same bytes (the pre-scan and LCM agree on every field); a step
// request that validates converts back (MakeStepRequest) to a message that validates to the
// same command.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>

#include "fuzz_input.h"

#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_layout.h"

namespace far::fuzz {
namespace {

using protocol::MessageType;
namespace wire = far_lcm;

// The larger of the daemon's and the client's caps: every decoder sees every size it allows.
constexpr size_t kMaxBytes = protocol::kMaxStepReplyBytes;

template <typename T>
void CheckRoundTrip(const T& message, const uint8_t* data, size_t size) {
  auto type = protocol::IdentifyMessage(data, size);
  FAR_FUZZ_CHECK(type && *type == protocol::internal::MessageTypeOf<T>::value);
  auto encoded = protocol::EncodeMessage(message);
  FAR_FUZZ_CHECK(encoded);
  FAR_FUZZ_CHECK(encoded->size() == size && std::memcmp(encoded->data(), data, size) == 0);
}

template <typename T>
std::optional<T> Decode(const uint8_t* data, size_t size) {
  auto message = protocol::DecodeMessage<T>(data, size, kMaxBytes);
  if (!message) {
    // A message of another version still passed the byte checks: the daemon answers it.
    if (message.error().code == ErrorCode::kVersionMismatch) {
      FAR_FUZZ_CHECK(protocol::DecodeMessageAnyVersion<T>(data, size, kMaxBytes));
    }
    return std::nullopt;
  }
  CheckRoundTrip(*message, data, size);
  return std::move(*message);
}

void CheckStepRequest(const wire::step_request_t& message) {
  auto command = protocol::ValidateStepRequest(message);
  if (!command) return;
  FAR_FUZZ_CHECK(CheckStepRequest(command->request).ok());
  const wire::step_request_t again = protocol::MakeStepRequest(
      command->session_id, command->request_id, command->step_id, command->ring_commit_sequence,
      command->request, command->timeout_ms);
  auto same = protocol::ValidateStepRequest(again);
  FAR_FUZZ_CHECK(same);
  FAR_FUZZ_CHECK(same->ring_commit_sequence == command->ring_commit_sequence);
  FAR_FUZZ_CHECK(same->timeout_ms == command->timeout_ms);
  const StepRequest& a = command->request;
  const StepRequest& b = same->request;
  FAR_FUZZ_CHECK(a.method == b.method && a.mechanism == b.mechanism &&
                 a.resolution == b.resolution && a.depth_format == b.depth_format &&
                 a.subobject_size == b.subobject_size && a.output == b.output);
  FAR_FUZZ_CHECK(a.distance.has_value() == b.distance.has_value());
  if (a.distance) FAR_FUZZ_CHECK(std::memcmp(&*a.distance, &*b.distance, sizeof(double)) == 0);
}

void CheckOpenSession(const wire::open_session_t& message) {
  auto params = protocol::ValidateOpenSession(message);
  if (!params) return;
  FAR_FUZZ_CHECK(!params->client_name.empty() &&
                 params->client_name.size() <= protocol::kMaxClientNameLength);
  for (const uint64_t bytes : {params->update_ring_bytes, params->reply_ring_bytes})
    FAR_FUZZ_CHECK(bytes == 0 || protocol::IsValidRingCapacity(bytes));
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  if (auto m = Decode<wire::open_session_t>(data, size)) CheckOpenSession(*m);
  if (auto m = Decode<wire::step_request_t>(data, size)) CheckStepRequest(*m);
  if (auto m = Decode<wire::step_reply_t>(data, size)) (void)protocol::ParseStepReply(*m);
  if (auto m = Decode<wire::step_status_t>(data, size))
    (void)protocol::ValidateSessionIds(MessageType::kStepStatus, m->session_id, m->request_id);
  if (auto m = Decode<wire::error_t>(data, size))
    (void)protocol::ValidateSessionIds(MessageType::kError, m->session_id, m->request_id);
  (void)Decode<wire::sealed_t>(data, size);
  (void)Decode<wire::status_request_t>(data, size);
  (void)Decode<wire::open_session_reply_t>(data, size);
  (void)Decode<wire::status_reply_t>(data, size);
  return 0;
}
