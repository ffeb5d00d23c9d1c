#include "far/protocol/session_auth.h"

#include <sodium.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace far::protocol {
namespace {

static_assert(crypto_auth_hmacsha512256_BYTES == kAuthBytes);
static_assert(crypto_auth_hmacsha512256_KEYBYTES == kSessionKeyBytes);

// libsodium must be initialized once before use; sodium_init is idempotent and thread-safe.
void EnsureSodium() {
  static const bool ok = [] {
    if (sodium_init() < 0) {
      std::fputs("far: libsodium failed to initialize\n", stderr);
      std::abort();
    }
    return true;
  }();
  (void)ok;
}

// Computes the tag of `encoded` as if its auth bytes were zero.
void ComputeTag(std::span<const uint8_t> encoded, const SessionKey& key, uint8_t tag[kAuthBytes]) {
  static constexpr uint8_t kZeros[kAuthBytes] = {};
  crypto_auth_hmacsha512256_state state;
  crypto_auth_hmacsha512256_init(&state, key.data(), key.size());
  crypto_auth_hmacsha512256_update(&state, encoded.data(), kAuthOffset);
  crypto_auth_hmacsha512256_update(&state, kZeros, kAuthBytes);
  crypto_auth_hmacsha512256_update(&state, encoded.data() + kAuthOffset + kAuthBytes,
                                   encoded.size() - kAuthOffset - kAuthBytes);
  crypto_auth_hmacsha512256_final(&state, tag);
  sodium_memzero(&state, sizeof(state));
}

}  // namespace

SessionKey NewSessionKey() {
  SessionKey key;
  RandomBytes(key.data(), key.size());
  return key;
}

void RandomBytes(uint8_t* bytes, size_t count) {
  EnsureSodium();
  randombytes_buf(bytes, count);
}

std::array<uint8_t, 32> HashBytes(std::span<const uint8_t> bytes) {
  EnsureSodium();
  std::array<uint8_t, 32> hash;
  crypto_generichash(hash.data(), hash.size(), bytes.data(), bytes.size(), nullptr, 0);
  return hash;
}

bool IsSessionMessage(MessageType type) {
  switch (type) {
    case MessageType::kCloseSession:
    case MessageType::kHeartbeat:
    case MessageType::kStepRequest:
    case MessageType::kStepReply:
    case MessageType::kError:
      return true;
    default:
      return false;
  }
}

Result<void> SignEncoded(std::span<uint8_t> encoded, const SessionKey& key) {
  if (encoded.size() < kAuthOffset + kAuthBytes) {
    return MakeError(ErrorCode::kInvalidArgument, "auth: " + std::to_string(encoded.size()) +
                                                      " bytes is too short for a session message");
  }
  EnsureSodium();
  uint8_t tag[kAuthBytes];
  ComputeTag(encoded, key, tag);
  std::memcpy(encoded.data() + kAuthOffset, tag, kAuthBytes);
  return {};
}

Result<void> VerifyEncoded(std::span<const uint8_t> encoded, const SessionKey& key) {
  if (encoded.size() < kAuthOffset + kAuthBytes) {
    return MakeError(ErrorCode::kParseError, "auth: " + std::to_string(encoded.size()) +
                                                 " bytes is too short for a session message");
  }
  EnsureSodium();
  uint8_t tag[kAuthBytes];
  ComputeTag(encoded, key, tag);
  // Constant time: the comparison does not leak how many leading bytes matched.
  if (crypto_verify_32(tag, encoded.data() + kAuthOffset) != 0) {
    return MakeError(ErrorCode::kPermissionDenied, "auth: the tag does not match the session key");
  }
  return {};
}

}  // namespace far::protocol
