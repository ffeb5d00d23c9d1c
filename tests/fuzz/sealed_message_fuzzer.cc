// Fuzz target sealed_message: what a client does with a datagram on its session's reply
// channel. OpenSealed (sealed_t decoding, session check, XChaCha20-Poly1305 authentication with
// the session key), then, as far::Client does with what opened: IdentifyMessage and the decoding
// of a step_reply_t (ReceiveStepReply, which follows a stub into the reply ring, and
// ParseStepReply), a step_status_t or an error_t. The session and its key are fixed
// (sealed_session.h), and its reply ring (private memory, fresh per input) holds one record: the
// protocol tests' sample step reply, written by the daemon's WriteShmReply, so a stub can name it.
//
// Input: uint8 mode, then
//   mode even: a datagram as received (any bytes);
//   mode odd:  int64 request_id, uint8 flip count, that many (uint16 offset, uint8 xor) flips,
//              then an inner message. The harness seals the inner message for session 3 as the
//              daemon does (SealEncoded), applies the flips to the sealed bytes (offset modulo
//              their size), and delivers the result.
//
// Oracles besides the sanitizers: in odd mode, sealed bytes the flips left unchanged open, with
// the request_id and the inner bytes they were sealed with; sealed bytes with any change do not
// open (every byte of a sealed_t is authenticated: fingerprint, version, session, sequence as
// additional data, nonce and box by the AEAD).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "fuzz_input.h"
#include "protocol/test_messages.h"
#include "protocol/test_ring.h"
#include "sealed_session.h"

#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"

namespace far::fuzz {
namespace {

using protocol::MessageType;
using protocol::testing::TestRing;
namespace wire = far_lcm;

constexpr int64_t kSessionId = kSealedSessionId;
// The client's cap (far::Client passes kMaxStepReplyBytes; smaller here so that the cap itself
// is reachable by the fuzzer's sizes).
constexpr size_t kMaxInnerBytes = protocol::kMaxControlMessageBytes;

protocol::SessionKey Key() { return SealedSessionKey(); }

// What far::Client::Impl::OnReply does with an opened message.
void Dispatch(std::span<const uint8_t> inner) {
  auto type = protocol::IdentifyMessage(inner.data(), inner.size());
  if (!type) return;
  if (*type == MessageType::kStepReply) {
    TestRing ring(protocol::kMinRingCapacity, "reply ring");
    protocol::RingWriter writer(ring.region());
    static const std::vector<uint8_t> sample =
        *protocol::EncodeMessage(protocol::testing::SampleStepReply());
    FAR_FUZZ_CHECK(protocol::WriteShmReply(writer, sample));
    protocol::RingReader reader(ring.region(), ring.data.size());
    auto full = protocol::ReceiveStepReply(inner, reader);
    if (full) (void)protocol::ParseStepReply(*full);
  } else if (*type == MessageType::kStepStatus) {
    (void)protocol::DecodeMessage<wire::step_status_t>(inner.data(), inner.size(),
                                                       protocol::kMaxControlMessageBytes);
  } else if (*type == MessageType::kError) {
    (void)protocol::DecodeMessage<wire::error_t>(inner.data(), inner.size(),
                                                 protocol::kMaxControlMessageBytes);
  }
}

void Received(std::span<const uint8_t> bytes) {
  auto opened = protocol::OpenSealed(bytes.data(), bytes.size(), kSessionId, Key(), kMaxInnerBytes);
  if (opened) Dispatch(opened->inner);
}

void Sealed(FuzzInput& in) {
  const auto request_id = in.Take<int64_t>();
  const uint8_t flips = in.Take<uint8_t>();
  std::vector<std::pair<uint16_t, uint8_t>> changes;
  for (uint8_t i = 0; i < flips; ++i) {
    const auto offset = in.Take<uint16_t>();
    changes.emplace_back(offset, in.Take<uint8_t>());
  }
  const auto inner = in.TakeBytes(in.left());
  auto sealed = protocol::SealEncoded(inner, kSessionId, request_id, Key());
  FAR_FUZZ_CHECK(sealed);
  std::vector<uint8_t> bytes = *sealed;
  for (const auto& [offset, mask] : changes) bytes[offset % bytes.size()] ^= mask;
  auto opened = protocol::OpenSealed(bytes.data(), bytes.size(), kSessionId, Key(), kMaxInnerBytes);
  if (bytes != *sealed) {
    FAR_FUZZ_CHECK(!opened);
    return;
  }
  // OpenSealed's cap is on the sealed bytes: the inner cap plus room for the sealed_t fields.
  if (bytes.size() > kMaxInnerBytes + 128) {
    FAR_FUZZ_CHECK(!opened);
    return;
  }
  FAR_FUZZ_CHECK(opened);
  FAR_FUZZ_CHECK(opened->request_id == request_id);
  FAR_FUZZ_CHECK(
      std::equal(opened->inner.begin(), opened->inner.end(), inner.begin(), inner.end()));
  Dispatch(opened->inner);
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::fuzz;
  FuzzInput in(data, size);
  if ((in.Take<uint8_t>() & 1) == 0) {
    Received(in.TakeBytes(in.left()));
  } else {
    Sealed(in);
  }
  return 0;
}
