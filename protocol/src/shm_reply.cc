#include "far/protocol/shm_reply.h"

#include <cstring>

#include "far/protocol/ring_layout.h"
#include "far/protocol/version.h"

namespace far::protocol {

bool ShouldUseShmReply(size_t encoded_bytes) { return encoded_bytes > kShmReplyThresholdBytes; }

Result<ShmReplyRef> WriteShmReply(RingWriter& reply_ring, std::span<const uint8_t> encoded) {
  StepReplyRecord fixed{};
  fixed.payload_size = encoded.size();
  const std::span<const uint8_t> body(
      reinterpret_cast<const uint8_t*>(&fixed) + sizeof(RecordHeader),
      sizeof(fixed) - sizeof(RecordHeader));
  auto position = reply_ring.Write(RecordType::kStepReply, {body, encoded});
  if (!position) return position.error();
  ShmReplyRef ref;
  ref.sequence = position->sequence;
  ref.index = position->index;
  ref.bytes = encoded.size();
  ref.hash = HashBytes(encoded);
  return ref;
}

namespace {

Error Mismatch(const ShmReplyRef& ref, const std::string& what) {
  return MakeError(ErrorCode::kParseError,
                   "reply ring: record " + std::to_string(ref.sequence) + ": " + what);
}

// The payload of a step_reply record (its bytes after the record header's fixed part) when it
// is the one `ref` names: index, size and hash as the stub says.
Result<std::vector<uint8_t>> CheckedPayload(const ShmReplyRef& ref, uint64_t index,
                                            std::span<const uint8_t> payload) {
  if (index != ref.index) {
    return Mismatch(ref, "index " + std::to_string(index) + " differs from the stub's " +
                             std::to_string(ref.index));
  }
  if (payload.size() != ref.bytes) {
    return Mismatch(ref, "payload_size " + std::to_string(payload.size()) +
                             " does not match the stub's " + std::to_string(ref.bytes) + " bytes");
  }
  if (HashBytes(payload) != ref.hash)
    return Mismatch(ref, "the payload's hash differs from the stub's");
  return std::vector<uint8_t>(payload.begin(), payload.end());
}

// The payload of a step_reply record read from the ring, after its type and size checks.
Result<std::span<const uint8_t>> RecordPayload(const ShmReplyRef& ref, const RawRecord& record) {
  if (record.header.type != static_cast<uint32_t>(RecordType::kStepReply)) {
    return Mismatch(ref, "type " + std::to_string(record.header.type) + " is not step_reply (16)");
  }
  if (record.bytes.size() < sizeof(StepReplyRecord)) {
    return Mismatch(ref, "size " + std::to_string(record.bytes.size()) + " is too small");
  }
  uint64_t payload_size = 0;
  std::memcpy(&payload_size, record.bytes.data() + offsetof(StepReplyRecord, payload_size),
              sizeof(payload_size));
  if (StepReplyRecordSize(payload_size) != record.bytes.size()) {
    return Mismatch(ref, "payload_size " + std::to_string(payload_size) + " in a " +
                             std::to_string(record.bytes.size()) + "-byte record does not fit it");
  }
  return std::span<const uint8_t>(record.bytes.data() + sizeof(StepReplyRecord), payload_size);
}

}  // namespace

void SkippedReplies::Keep(uint64_t sequence, uint64_t index, std::vector<uint8_t> payload) {
  records_.push_back({sequence, index, std::move(payload)});
  while (records_.size() > kMaxRecords) records_.pop_front();
}

Result<std::vector<uint8_t>> SkippedReplies::Take(const ShmReplyRef& ref) {
  for (auto it = records_.begin(); it != records_.end(); ++it) {
    if (it->sequence != ref.sequence) continue;
    const Record record = std::move(*it);
    records_.erase(it);
    return CheckedPayload(ref, record.index, record.payload);
  }
  return MakeError(ErrorCode::kNotFound, "reply ring: record " + std::to_string(ref.sequence) +
                                             " was already read and is not kept");
}

Result<std::vector<uint8_t>> ReadShmReply(RingReader& reply_ring, const ShmReplyRef& ref,
                                          SkippedReplies* skipped) {
  while (true) {
    if (reply_ring.last_sequence() >= ref.sequence) {
      // Read past already: a stub sent again for a record skipped on the way to a later one.
      if (skipped != nullptr) {
        if (auto kept = skipped->Take(ref); kept || kept.error().code != ErrorCode::kNotFound)
          return kept;
      }
      return MakeError(ErrorCode::kNotFound, "reply ring: record " + std::to_string(ref.sequence) +
                                                 " was already read (last read: " +
                                                 std::to_string(reply_ring.last_sequence()) + ")");
    }
    auto next = reply_ring.ReadNext();
    if (!next) return next.error();
    if (!next->has_value()) {
      return MakeError(ErrorCode::kNotFound, "reply ring: record " + std::to_string(ref.sequence) +
                                                 " is not in the ring (it holds records up to " +
                                                 std::to_string(reply_ring.last_sequence()) + ")");
    }
    const RawRecord& record = **next;
    auto payload = RecordPayload(ref, record);
    // An older reply whose stub never arrived (or comes later): skip it, and keep it.
    if (record.header.sequence < ref.sequence) {
      if (skipped != nullptr && payload) {
        skipped->Keep(record.header.sequence, record.index,
                      std::vector<uint8_t>(payload->begin(), payload->end()));
      }
      continue;
    }
    if (!payload) return payload.error();
    return CheckedPayload(ref, record.index, *payload);
  }
}

far_lcm::step_reply_t MakeShmReplyStub(const far_lcm::step_reply_t& full, const ShmReplyRef& ref) {
  far_lcm::step_reply_t stub{};
  stub.protocol_version = full.protocol_version;
  stub.session_id = full.session_id;
  std::memset(stub.auth, 0, sizeof(stub.auth));
  stub.request_id = full.request_id;
  stub.step_id = full.step_id;
  stub.ring_applied_sequence = full.ring_applied_sequence;
  stub.status = full.status;
  stub.status_name = full.status_name;
  stub.message = full.message;
  stub.output = full.output;
  stub.reply_in_shm = true;
  stub.shm_reply_sequence = static_cast<int64_t>(ref.sequence);
  stub.shm_reply_index = static_cast<int64_t>(ref.index);
  stub.shm_reply_bytes = static_cast<int64_t>(ref.bytes);
  std::memcpy(stub.shm_reply_hash, ref.hash.data(), ref.hash.size());
  stub.num_pcs_objects = 0;
  stub.num_object_pairs = 0;
  stub.num_pcs_primitive_objects = 0;
  stub.num_pcs_primitives = 0;
  stub.num_contacts = 0;
  stub.num_distance_pairs = 0;
  stub.num_stages = 0;
  stub.total_ms = full.total_ms;
  stub.primitives_rendered = 0;
  stub.draws = 0;
  stub.queries = 0;
  stub.bytes_uploaded = 0;
  stub.object_pairs_considered = 0;
  stub.pairs_considered = 0;
  stub.pairs_tested = 0;
  stub.object_radius = 0;
  stub.primitive_radius = 0;
  return stub;
}

Result<std::vector<uint8_t>> EncodeStepReplyInner(const far_lcm::step_reply_t& full,
                                                  RingWriter& reply_ring) {
  auto encoded = EncodeMessage(full);
  if (!encoded) return encoded.error();
  if (!ShouldUseShmReply(encoded->size())) return encoded;
  auto ref = WriteShmReply(reply_ring, *encoded);
  if (!ref) return ref.error();
  return EncodeMessage(MakeShmReplyStub(full, *ref));
}

Result<std::vector<uint8_t>> EncodeStepReplyForTransport(const far_lcm::step_reply_t& full,
                                                         RingWriter& reply_ring,
                                                         const SessionKey& key,
                                                         int64_t seal_sequence) {
  auto inner = EncodeStepReplyInner(full, reply_ring);
  if (!inner) return inner.error();
  return SealEncoded(*inner, full.session_id, seal_sequence, key);
}

Result<far_lcm::step_reply_t> ReceiveStepReply(std::span<const uint8_t> inner,
                                               RingReader& reply_ring, SkippedReplies* skipped) {
  auto reply = DecodeMessage<far_lcm::step_reply_t>(inner.data(), inner.size(), kMaxStepReplyBytes);
  if (!reply) return reply.error();
  if (!reply->reply_in_shm) return reply;

  // A stub: fetch, check and decode the full reply.
  const far_lcm::step_reply_t& stub = *reply;
  if (stub.shm_reply_sequence <= 0 || stub.shm_reply_index < 0 || stub.shm_reply_bytes <= 0) {
    return MakeError(ErrorCode::kParseError, "step_reply_t.shm_reply_*: sequence " +
                                                 std::to_string(stub.shm_reply_sequence) +
                                                 ", index " + std::to_string(stub.shm_reply_index) +
                                                 ", bytes " + std::to_string(stub.shm_reply_bytes) +
                                                 " do not name a record");
  }
  ShmReplyRef ref;
  ref.sequence = static_cast<uint64_t>(stub.shm_reply_sequence);
  ref.index = static_cast<uint64_t>(stub.shm_reply_index);
  ref.bytes = static_cast<uint64_t>(stub.shm_reply_bytes);
  std::memcpy(ref.hash.data(), stub.shm_reply_hash, ref.hash.size());
  auto payload = ReadShmReply(reply_ring, ref, skipped);
  if (!payload) return payload.error();
  auto full =
      DecodeMessage<far_lcm::step_reply_t>(payload->data(), payload->size(), kMaxStepReplyBytes);
  if (!full) return full.error();
  if (full->reply_in_shm || full->session_id != stub.session_id ||
      full->request_id != stub.request_id || full->step_id != stub.step_id) {
    return MakeError(ErrorCode::kParseError, "reply ring: record " + std::to_string(ref.sequence) +
                                                 " holds a reply for another request");
  }
  return full;
}

}  // namespace far::protocol
