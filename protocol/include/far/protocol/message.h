#pragma once

// Safe encoding and decoding of the far_lcm message types.
//
// Every byte a client sends passes DecodeMessage before anything else reads it:
//   1. the byte size against a cap (before anything is allocated);
//   2. the LCM fingerprint (the message type);
//   3. a pre-scan of the encoding against the type's schema: every array length is >= 0 and
//      its elements fit in the bytes that are left, every string has its length, its NUL and
//      no other NUL, and the fields end exactly at the end of the bytes. LCM 1.3.1's generated
//      C++ `decode` resizes a std::vector to the length read from the message *before* it
//      checks that the bytes are there (a 40-byte message claiming 2^31 elements allocates
//      8 GiB), and a string length of 0 or less makes it throw; the pre-scan makes `decode`
//      safe: after it, no allocation exceeds a small multiple of the message size;
//   4. LCM's own decode, which must consume exactly `size` bytes;
//   5. protocol_version == kProtocolVersion (kVersionMismatch).
// Meaning (ranges, names, counts) is checked next by message_validate.h; authentication of
// session messages by session_auth.h.
//
// Never subscribe with lcm-cpp's typed handlers on the daemon (they call `decode` unguarded):
// subscribe with the raw `const lcm::ReceiveBuffer*` form and call DecodeMessage.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

#include "far_lcm/error_t.hpp"
#include "far_lcm/open_session_reply_t.hpp"
#include "far_lcm/open_session_t.hpp"
#include "far_lcm/recording_header_t.hpp"
#include "far_lcm/ring_record_t.hpp"
#include "far_lcm/sealed_t.hpp"
#include "far_lcm/status_reply_t.hpp"
#include "far_lcm/status_request_t.hpp"
#include "far_lcm/step_reply_t.hpp"
#include "far_lcm/step_request_t.hpp"
#include "far_lcm/step_status_t.hpp"

#include "far/base/result.h"
#include "far/protocol/version.h"

namespace far::protocol {

/// The far_lcm message types.
enum class MessageType {
  kOpenSession,
  kOpenSessionReply,
  kSealed,
  kStepStatus,
  kStepRequest,
  kStepReply,
  kError,
  kStatusRequest,
  kStatusReply,
  kRecordingHeader,  ///< far recordings only (recording.h), never on the bus
  kRingRecord,       ///< far recordings only (recording.h), never on the bus
};

/// Returns the LCM type name, e.g. "step_request_t".
std::string_view ToString(MessageType type);

/// Tells which far_lcm type an encoded message is, by its 8-byte LCM fingerprint (several
/// types share a session channel). Errors: kParseError when `size` < 8 or the fingerprint is
/// not one of ours. Reads only the first 8 bytes.
Result<MessageType> IdentifyMessage(const void* data, size_t size);

namespace internal {

template <typename T>
struct MessageTypeOf;
template <>
struct MessageTypeOf<far_lcm::open_session_t> {
  static constexpr MessageType value = MessageType::kOpenSession;
};
template <>
struct MessageTypeOf<far_lcm::open_session_reply_t> {
  static constexpr MessageType value = MessageType::kOpenSessionReply;
};
template <>
struct MessageTypeOf<far_lcm::sealed_t> {
  static constexpr MessageType value = MessageType::kSealed;
};
template <>
struct MessageTypeOf<far_lcm::step_status_t> {
  static constexpr MessageType value = MessageType::kStepStatus;
};
template <>
struct MessageTypeOf<far_lcm::step_request_t> {
  static constexpr MessageType value = MessageType::kStepRequest;
};
template <>
struct MessageTypeOf<far_lcm::step_reply_t> {
  static constexpr MessageType value = MessageType::kStepReply;
};
template <>
struct MessageTypeOf<far_lcm::error_t> {
  static constexpr MessageType value = MessageType::kError;
};
template <>
struct MessageTypeOf<far_lcm::status_request_t> {
  static constexpr MessageType value = MessageType::kStatusRequest;
};
template <>
struct MessageTypeOf<far_lcm::status_reply_t> {
  static constexpr MessageType value = MessageType::kStatusReply;
};
template <>
struct MessageTypeOf<far_lcm::recording_header_t> {
  static constexpr MessageType value = MessageType::kRecordingHeader;
};
template <>
struct MessageTypeOf<far_lcm::ring_record_t> {
  static constexpr MessageType value = MessageType::kRingRecord;
};

/// Steps 1-3 of DecodeMessage: cap, fingerprint, schema pre-scan.
Result<void> CheckEncoding(MessageType type, const void* data, size_t size, size_t max_size);
/// Step 5: the protocol version.
Result<void> CheckProtocolVersion(MessageType type, int32_t version);

}  // namespace internal

/// Decodes an untrusted encoded message of type T (steps 1-5 above).
/// Errors: kLimitExceeded (size > max_size or an allocation failed), kParseError (fingerprint,
/// malformed encoding, trailing bytes; the message names the field), kVersionMismatch
/// ("step_request_t.protocol_version: got 2, expected 1"). Thread-safe; never throws.
/// As DecodeMessage, without the protocol_version check: for answering a peer of another
/// version in terms it can read (the bytes are still size-checked and pre-scanned).
template <typename T>
Result<T> DecodeMessageAnyVersion(const void* data, size_t size, size_t max_size) {
  constexpr MessageType kType = internal::MessageTypeOf<T>::value;
  if (auto ok = internal::CheckEncoding(kType, data, size, max_size); !ok) return ok.error();
  T message;
  try {
    // The pre-scan proved every length; decode now allocates at most what the bytes hold.
    const int decoded = message.decode(data, 0, static_cast<int>(size));
    if (decoded != static_cast<int>(size)) {
      return MakeError(ErrorCode::kParseError,
                       std::string(ToString(kType)) + ": LCM decode failed (returned " +
                           std::to_string(decoded) + " for " + std::to_string(size) + " bytes)");
    }
  } catch (const std::exception& e) {
    return MakeError(ErrorCode::kLimitExceeded,
                     std::string(ToString(kType)) + ": decoding failed: " + e.what());
  }
  return message;
}

template <typename T>
Result<T> DecodeMessage(const void* data, size_t size, size_t max_size) {
  auto message = DecodeMessageAnyVersion<T>(data, size, max_size);
  if (!message) return message;
  if (auto ok = internal::CheckProtocolVersion(internal::MessageTypeOf<T>::value,
                                               message->protocol_version);
      !ok) {
    return ok.error();
  }
  return message;
}

/// Encodes a message (trusted, our own). Errors: kLimitExceeded when the encoding would be
/// larger than 2^31 - 1 bytes (LCM's limit); kInternal when LCM's encode fails.
template <typename T>
Result<std::vector<uint8_t>> EncodeMessage(const T& message) {
  const int64_t size = static_cast<int64_t>(message.getEncodedSize());
  if (size <= 0) {
    return MakeError(ErrorCode::kLimitExceeded,
                     std::string(ToString(internal::MessageTypeOf<T>::value)) +
                         ": the encoding is too large for LCM");
  }
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (message.encode(bytes.data(), 0, static_cast<int>(size)) != size) {
    return MakeError(
        ErrorCode::kInternal,
        std::string(ToString(internal::MessageTypeOf<T>::value)) + ": LCM encode failed");
  }
  return bytes;
}

}  // namespace far::protocol
