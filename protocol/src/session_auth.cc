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

// The keys derived from a session key: one per purpose, never the session key itself.
enum class KeyPurpose : uint64_t { kRequestMac = 1, kReplyBox = 2 };

SessionKey DeriveKey(const SessionKey& key, KeyPurpose purpose) {
  static_assert(crypto_kdf_KEYBYTES == kSessionKeyBytes);
  SessionKey subkey;
  crypto_kdf_derive_from_key(subkey.data(), subkey.size(), static_cast<uint64_t>(purpose),
                             "farsessn", key.data());
  return subkey;
}

// Computes the tag of `encoded` as if its auth bytes were zero.
void ComputeTag(std::span<const uint8_t> encoded, const SessionKey& key, uint8_t tag[kAuthBytes]) {
  static constexpr uint8_t kZeros[kAuthBytes] = {};
  SessionKey mac_key = DeriveKey(key, KeyPurpose::kRequestMac);
  crypto_auth_hmacsha512256_state state;
  crypto_auth_hmacsha512256_init(&state, mac_key.data(), mac_key.size());
  sodium_memzero(mac_key.data(), mac_key.size());
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
    case MessageType::kStepStatus:
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

namespace {

// The sealed_t fields before the nonce, as LCM encodes them (big-endian, after the type's
// fingerprint): the additional data of the AEAD.
constexpr size_t kSealedHeaderBytes = 8 + 4 + 8 + 8;

std::array<uint8_t, kSealedHeaderBytes> SealedHeader(int32_t version, int64_t session_id,
                                                     int64_t request_id) {
  std::array<uint8_t, kSealedHeaderBytes> bytes{};
  size_t pos = 0;
  auto put = [&](uint64_t value, int width) {
    for (int i = width - 1; i >= 0; --i) bytes[pos++] = static_cast<uint8_t>(value >> (8 * i));
  };
  put(static_cast<uint64_t>(far_lcm::sealed_t::getHash()), 8);
  put(static_cast<uint32_t>(version), 4);
  put(static_cast<uint64_t>(session_id), 8);
  put(static_cast<uint64_t>(request_id), 8);
  return bytes;
}

constexpr size_t kBoxOverhead = crypto_aead_xchacha20poly1305_ietf_ABYTES;
static_assert(crypto_aead_xchacha20poly1305_ietf_NPUBBYTES == 24);

}  // namespace

Result<std::vector<uint8_t>> SealEncoded(std::span<const uint8_t> inner, int64_t session_id,
                                         int64_t request_id, const SessionKey& key) {
  if (inner.size() > static_cast<size_t>(INT32_MAX) - kBoxOverhead - 128) {
    return MakeError(ErrorCode::kLimitExceeded, "sealed_t: the message is too large for LCM");
  }
  EnsureSodium();
  far_lcm::sealed_t sealed{};
  sealed.protocol_version = kProtocolVersion;
  sealed.session_id = session_id;
  sealed.request_id = request_id;
  randombytes_buf(sealed.nonce, sizeof(sealed.nonce));
  sealed.box_bytes = static_cast<int32_t>(inner.size() + kBoxOverhead);
  sealed.box.resize(static_cast<size_t>(sealed.box_bytes));
  const auto ad = SealedHeader(sealed.protocol_version, session_id, request_id);
  SessionKey box_key = DeriveKey(key, KeyPurpose::kReplyBox);
  unsigned long long written = 0;
  crypto_aead_xchacha20poly1305_ietf_encrypt(sealed.box.data(), &written, inner.data(),
                                             inner.size(), ad.data(), ad.size(), nullptr,
                                             sealed.nonce, box_key.data());
  sodium_memzero(box_key.data(), box_key.size());
  return EncodeMessage(sealed);
}

Result<Unsealed> OpenSealed(const void* data, size_t size, int64_t session_id,
                            const SessionKey& key, size_t max_inner_bytes) {
  auto sealed = DecodeMessage<far_lcm::sealed_t>(data, size, max_inner_bytes + 128);
  if (!sealed) return sealed.error();
  if (sealed->session_id != session_id) {
    return MakeError(ErrorCode::kPermissionDenied, "sealed_t: for session " +
                                                       std::to_string(sealed->session_id) +
                                                       ", not " + std::to_string(session_id));
  }
  if (sealed->box.size() < kBoxOverhead) {
    return MakeError(ErrorCode::kParseError, "sealed_t.box: shorter than its tag");
  }
  EnsureSodium();
  const auto ad = SealedHeader(sealed->protocol_version, sealed->session_id, sealed->request_id);
  Unsealed out;
  out.request_id = sealed->request_id;
  out.inner.resize(sealed->box.size() - kBoxOverhead);
  SessionKey box_key = DeriveKey(key, KeyPurpose::kReplyBox);
  unsigned long long opened = 0;
  const int status = crypto_aead_xchacha20poly1305_ietf_decrypt(
      out.inner.data(), &opened, nullptr, sealed->box.data(), sealed->box.size(), ad.data(),
      ad.size(), sealed->nonce, box_key.data());
  sodium_memzero(box_key.data(), box_key.size());
  if (status != 0) {
    return MakeError(ErrorCode::kPermissionDenied,
                     "sealed_t: does not open with the session key (forged or altered)");
  }
  out.inner.resize(static_cast<size_t>(opened));
  return out;
}

}  // namespace far::protocol
