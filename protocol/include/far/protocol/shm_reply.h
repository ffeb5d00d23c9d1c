#pragma once

// Large step replies through the segment's reply ring instead of LCM.
//
// LCM over udpm splits a message into ~64 KB datagrams and drops the whole message when one
// fragment is lost; the kernel drops datagrams when the receive buffer overflows, and a reply
// larger than the socket buffer never arrives (docs/protocol.md has the measurements). Above
// kShmReplyThresholdBytes the daemon writes the full encoded step_reply_t into the reply ring
// (a kStepReply record) and publishes a small stub on LCM that names the record (sequence,
// index, size) and its BLAKE2b-256 hash; the stub is sealed, so the hash binds the payload to
// the session key. The client reads the record, checks it against the stub and decodes it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "far/base/result.h"
#include "far/protocol/message.h"
#include "far/protocol/ring.h"
#include "far/protocol/session_auth.h"

namespace far::protocol {

/// Encoded step replies larger than this go through the reply ring. LCM 1.3.1's udpm sends a
/// message whose channel name + 1 + payload is at most 65499 bytes as one datagram and splits
/// larger ones into fragments that are lost as a whole when one is dropped; 63 KiB keeps every
/// inline reply in one datagram with room for the channel name. Measured in docs/protocol.md:
/// above this size the ring is never slower and never loses a reply.
inline constexpr size_t kShmReplyThresholdBytes = size_t{63} << 10;

/// True when an encoded step reply of `encoded_bytes` should go through the reply ring.
bool ShouldUseShmReply(size_t encoded_bytes);

/// Where a reply went in the reply ring, as the stub names it.
struct ShmReplyRef {
  uint64_t sequence = 0;           ///< reply ring record sequence
  uint64_t index = 0;              ///< reply ring byte index of the record
  uint64_t bytes = 0;              ///< size of the encoded step_reply_t
  std::array<uint8_t, 32> hash{};  ///< HashBytes of the encoded step_reply_t
};

/// Daemon: writes an encoded step reply into the reply ring. Errors: kBusy (the client has
/// not read enough earlier replies), kLimitExceeded (larger than the ring), kParseError (the
/// client's read index is inconsistent, segment truncated).
Result<ShmReplyRef> WriteShmReply(RingWriter& reply_ring, std::span<const uint8_t> encoded);

/// Client: the reply records ReadShmReply skipped to reach a later one (their stubs were lost
/// or had not come yet), kept so that a stub the daemon sends again still finds its record.
/// Bounded: the newest kMaxRecords. Not thread-safe (the client's receive thread owns it).
class SkippedReplies {
 public:
  static constexpr size_t kMaxRecords = 4;
  /// Keeps a skipped record's sequence, index and payload, dropping the oldest beyond the bound.
  void Keep(uint64_t sequence, uint64_t index, std::vector<uint8_t> payload);
  /// The payload kept for `ref`, checked like a record in the ring (index, size, hash), and
  /// forgotten; kNotFound when none is kept, kParseError when it does not match the stub.
  Result<std::vector<uint8_t>> Take(const ShmReplyRef& ref);

 private:
  struct Record {
    uint64_t sequence = 0, index = 0;
    std::vector<uint8_t> payload;
  };
  std::deque<Record> records_;
};

/// Client: reads the record `ref` names, skipping older records (replies whose stubs were
/// lost: kept in `skipped` when given), and returns its payload after checking type, index,
/// size and hash. A record already read past is taken from `skipped`. Errors: kNotFound (not
/// in the ring, or already read past and not kept), kParseError (mismatch, ring corrupt).
Result<std::vector<uint8_t>> ReadShmReply(RingReader& reply_ring, const ShmReplyRef& ref,
                                          SkippedReplies* skipped = nullptr);

/// Returns the stub for `full`: the same ids and status, reply_in_shm true, the shm_reply_*
/// fields from `ref`, every array empty and every count 0 (auth zero: sign it).
far_lcm::step_reply_t MakeShmReplyStub(const far_lcm::step_reply_t& full, const ShmReplyRef& ref);

/// Daemon, one call per reply: encodes `full`; when ShouldUseShmReply, writes it into the
/// reply ring and returns the encoding of a stub instead. The result is what travels inside
/// the sealed_t, and what the daemon keeps to answer a repeated request for the step. Errors:
/// those of EncodeMessage and WriteShmReply (the caller then sends MakeStepErrorReply).
Result<std::vector<uint8_t>> EncodeStepReplyInner(const far_lcm::step_reply_t& full,
                                                  RingWriter& reply_ring);

/// Daemon: EncodeStepReplyInner, sealed; returns the sealed_t bytes (daemon -> client sequence
/// `seal_sequence`) to publish on the session's reply channel. Errors: those of
/// EncodeStepReplyInner and SealEncoded (the caller then publishes MakeStepErrorReply instead).
Result<std::vector<uint8_t>> EncodeStepReplyForTransport(const far_lcm::step_reply_t& full,
                                                         RingWriter& reply_ring,
                                                         const SessionKey& key,
                                                         int64_t seal_sequence);

/// Client, one call per step_reply_t taken out of a sealed_t (OpenSealed authenticated it):
/// decodes it (cap kMaxStepReplyBytes), and when it is a stub reads, checks and decodes the
/// full reply from the reply ring (its ids must match the stub's). Returns the full reply; its
/// status may say the step failed (ParseStepReply turns it into a StepResult or an Error).
/// Errors: those of DecodeMessage and ReadShmReply (`skipped` as there).
Result<far_lcm::step_reply_t> ReceiveStepReply(std::span<const uint8_t> inner,
                                               RingReader& reply_ring,
                                               SkippedReplies* skipped = nullptr);

}  // namespace far::protocol
