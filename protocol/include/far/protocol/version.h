#pragma once

// The protocol version every LCM message carries, and the byte caps a receiver checks before it
// decodes anything.

#include <cstddef>
#include <cstdint>

namespace far::protocol {

/// Carried in every far_lcm message's `protocol_version`; bumped with every change of meaning
/// (a change of a message's fields also changes its LCM fingerprint).
inline constexpr int32_t kProtocolVersion = 5;

/// Byte caps checked before decoding. Control messages (open, step and status requests, open
/// reply, step status, error) are small; step replies may be large (shm path), and a sealed
/// message is its inner message plus 64 bytes.
inline constexpr size_t kMaxControlMessageBytes = 4096;
inline constexpr size_t kMaxStatusReplyBytes = size_t{1} << 20;
inline constexpr size_t kMaxStepReplyBytes = size_t{256} << 20;

}  // namespace far::protocol
