#pragma once

// The session of the sealed_message target, shared with the seed writer (make_seeds.cc) so
// that seeds can be sealed with its key.

#include <cstddef>
#include <cstdint>

#include "far/protocol/session_auth.h"

namespace far::fuzz {

inline constexpr int64_t kSealedSessionId = 3;

/// A fixed key: the target is about what a client does with what arrives, not about keys.
inline protocol::SessionKey SealedSessionKey() {
  protocol::SessionKey key;
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(0x40 + i);
  return key;
}

}  // namespace far::fuzz
