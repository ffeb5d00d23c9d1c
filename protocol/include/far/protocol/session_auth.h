#pragma once

// Authentication and privacy of session messages. The daemon makes a random 32-byte key per
// session and writes it into the session's shared-memory segment header; the segment reaches
// only the session's client (a file descriptor over the daemon's local socket), so the key
// never travels over LCM. Two keys are derived from it (crypto_kdf, context "farsessn"):
//  - the request key: every step_request_t starts with
//      int32_t protocol_version; int64_t session_id; byte auth[32]; int64_t request_id; ...
//    and `auth` is the HMAC-SHA-512-256 tag (libsodium crypto_auth) of its whole LCM encoding
//    with the 32 auth bytes zeroed. A tag proves knowledge of the key without revealing it
//    (LCM udpm is multicast: any local user can read any channel);
//  - the reply key: everything the daemon publishes for a session is sealed (sealed_t:
//    XChaCha20-Poly1305), so that only the session's client can read it.
// Replays are stopped by the receiver: request_id must grow strictly per session and
// direction.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "far/base/result.h"
#include "far/protocol/message.h"

namespace far::protocol {

inline constexpr size_t kSessionKeyBytes = 32;
using SessionKey = std::array<uint8_t, kSessionKeyBytes>;

/// Byte offset and length of `auth` in the encoding of every session message:
/// fingerprint (8) + protocol_version (4) + session_id (8).
inline constexpr size_t kAuthOffset = 20;
inline constexpr size_t kAuthBytes = 32;

/// Returns a fresh key from libsodium's CSPRNG (randombytes_buf). Thread-safe.
SessionKey NewSessionKey();

/// Fills `bytes` (@pre at least `count` bytes) with CSPRNG output. Thread-safe.
void RandomBytes(uint8_t* bytes, size_t count);

/// Returns the BLAKE2b-256 hash (crypto_generichash, no key) of `bytes`. Thread-safe.
std::array<uint8_t, 32> HashBytes(std::span<const uint8_t> bytes);

/// True for the message types that carry session_id and auth at the fixed offsets.
bool IsSessionMessage(MessageType type);

/// Writes the tag into the encoding of a session message in place (zeroes the auth bytes,
/// computes the tag, writes it). Errors: kInvalidArgument when `encoded` is shorter than
/// kAuthOffset + kAuthBytes.
Result<void> SignEncoded(std::span<uint8_t> encoded, const SessionKey& key);

/// Checks the tag of an encoded session message in constant time, without copying it.
/// Errors: kPermissionDenied ("auth: the tag does not match the session key"),
/// kParseError when `encoded` is too short.
Result<void> VerifyEncoded(std::span<const uint8_t> encoded, const SessionKey& key);

/// Daemon: seals the encoding of a session message (step_reply_t, step_status_t, error_t) into
/// the encoding of a sealed_t for `session_id` with daemon -> client sequence `request_id`.
/// Errors: kLimitExceeded when the result would exceed LCM's limit.
Result<std::vector<uint8_t>> SealEncoded(std::span<const uint8_t> inner, int64_t session_id,
                                         int64_t request_id, const SessionKey& key);

/// What OpenSealed returns: the daemon's sequence number and the inner message's encoding.
struct Unsealed {
  int64_t request_id = 0;
  std::vector<uint8_t> inner;
};

/// Client: decodes a sealed_t (cap: max_inner_bytes + 64), checks that it is for `session_id`
/// and decrypts it. Errors: those of DecodeMessage, kPermissionDenied (another session, or the
/// box does not open with this key: forged, altered or moved).
Result<Unsealed> OpenSealed(const void* data, size_t size, int64_t session_id,
                            const SessionKey& key, size_t max_inner_bytes);

/// Encodes a session message and signs it. Errors: as EncodeMessage.
template <typename T>
Result<std::vector<uint8_t>> EncodeSigned(const T& message, const SessionKey& key) {
  static_assert(
      requires {
        message.session_id;
        message.auth;
      },
      "EncodeSigned is for session messages");
  auto bytes = EncodeMessage(message);
  if (!bytes) return bytes.error();
  if (auto ok = SignEncoded(*bytes, key); !ok) return ok.error();
  return bytes;
}

}  // namespace far::protocol
