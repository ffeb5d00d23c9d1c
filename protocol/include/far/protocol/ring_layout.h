#pragma once

// The binary layout of a session's shared-memory segment: a header with the ring indices, the
// update ring (client -> daemon mesh updates) and the reply ring (daemon -> client large step
// replies). Both processes run on one host: integers and doubles are in host byte order
// (little-endian x86-64 / aarch64), and offsets are from the start of the segment, never
// pointers. Every incompatible change bumps kLayoutVersion; tests/protocol/ring_layout_test.cc
// pins every size and offset below. docs/protocol.md describes the rules in prose.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace far::protocol {

/// "FARRING\0" read as a little-endian uint64 (the bytes 'F','A','R','R','I','N','G',0).
inline constexpr uint64_t kSegmentMagic = 0x00474E4952524146ull;
/// Bumped with every incompatible change of anything in this file.
inline constexpr uint32_t kLayoutVersion = 1;
/// Ring regions start on this boundary (a page) inside the segment.
inline constexpr uint64_t kRingAlignment = 4096;
/// Smallest and largest ring capacity in bytes (powers of two).
inline constexpr uint64_t kMinRingCapacity = uint64_t{64} << 10;
inline constexpr uint64_t kMaxRingCapacity = uint64_t{1} << 30;
/// Every record's total size is a multiple of this.
inline constexpr uint32_t kRecordAlignment = 8;

/// The segment header at offset 0. The daemon writes the constant part once when it creates
/// the segment and never reads it back (it keeps a private copy); the client checks it once
/// when it maps the segment. Each index has its own cache line and one writer:
///   update_write_index: client (producer of the update ring)
///   update_read_index:  daemon (consumer of the update ring)
///   reply_write_index:  daemon (producer of the reply ring)
///   reply_read_index:   client (consumer of the reply ring)
/// An index counts bytes written or consumed since the ring was created (it never wraps in
/// practice: 2^64 bytes); the byte at index i lives at ring offset i & (capacity - 1).
struct SegmentHeader {
  uint64_t magic;                 ///< kSegmentMagic
  uint32_t layout_version;        ///< kLayoutVersion
  uint32_t header_size;           ///< sizeof(SegmentHeader), bytes
  uint64_t segment_size;          ///< bytes of the whole segment (header page + both rings)
  uint64_t session_id;            ///< the session this segment belongs to
  uint64_t update_ring_offset;    ///< bytes from the segment start; multiple of kRingAlignment
  uint64_t update_ring_capacity;  ///< bytes; a power of two in [kMinRingCapacity, kMaxRingCapacity]
  uint64_t reply_ring_offset;     ///< bytes from the segment start; multiple of kRingAlignment
  uint64_t reply_ring_capacity;   ///< bytes; a power of two in [kMinRingCapacity, kMaxRingCapacity]
  uint8_t session_key[32];        ///< MAC key of the session's LCM messages (session_auth.h)
  uint8_t reserved[32];           ///< zero
  alignas(64) std::atomic<uint64_t> update_write_index;  ///< bytes; written by the client
  alignas(64) std::atomic<uint64_t> update_read_index;   ///< bytes; written by the daemon
  alignas(64) std::atomic<uint64_t> reply_write_index;   ///< bytes; written by the daemon
  alignas(64) std::atomic<uint64_t> reply_read_index;    ///< bytes; written by the client
};

static_assert(std::atomic<uint64_t>::is_always_lock_free, "ring indices must be lock-free");
static_assert(sizeof(std::atomic<uint64_t>) == 8);
static_assert(std::is_standard_layout_v<SegmentHeader>);
static_assert(sizeof(SegmentHeader) == 384);
static_assert(sizeof(SegmentHeader) <= kRingAlignment);
static_assert(offsetof(SegmentHeader, magic) == 0);
static_assert(offsetof(SegmentHeader, layout_version) == 8);
static_assert(offsetof(SegmentHeader, header_size) == 12);
static_assert(offsetof(SegmentHeader, segment_size) == 16);
static_assert(offsetof(SegmentHeader, session_id) == 24);
static_assert(offsetof(SegmentHeader, update_ring_offset) == 32);
static_assert(offsetof(SegmentHeader, update_ring_capacity) == 40);
static_assert(offsetof(SegmentHeader, reply_ring_offset) == 48);
static_assert(offsetof(SegmentHeader, reply_ring_capacity) == 56);
static_assert(offsetof(SegmentHeader, session_key) == 64);
static_assert(offsetof(SegmentHeader, reserved) == 96);
static_assert(offsetof(SegmentHeader, update_write_index) == 128);
static_assert(offsetof(SegmentHeader, update_read_index) == 192);
static_assert(offsetof(SegmentHeader, reply_write_index) == 256);
static_assert(offsetof(SegmentHeader, reply_read_index) == 320);

/// Record types. Update ring: kAddObject .. kSetVertices. Reply ring: kStepReply.
enum class RecordType : uint32_t {
  kAddObject = 1,
  kRemoveObject = 2,
  kSetPose = 3,
  kSetVertices = 4,
  kStepReply = 16,
};

/// Motion kinds in an add_object record (far::Motion).
enum class WireMotion : uint32_t { kStatic = 0, kRigid = 1, kDeformable = 2 };

/// Starts every record. A record is `size` contiguous bytes of the ring's byte stream; it may
/// wrap around the end of the ring (the bytes continue at ring offset 0). Records follow each
/// other without gaps and their sequences count 1, 2, 3, ... per ring.
struct RecordHeader {
  uint32_t type;      ///< RecordType
  uint32_t size;      ///< total bytes including this header and trailing padding; multiple of 8
  uint64_t sequence;  ///< 1 for the first record of the ring, then +1 per record
};
static_assert(sizeof(RecordHeader) == 16);
static_assert(offsetof(RecordHeader, type) == 0);
static_assert(offsetof(RecordHeader, size) == 4);
static_assert(offsetof(RecordHeader, sequence) == 8);

/// A pose X_WO as 7 doubles: translation x, y, z (world units), then the unit rotation
/// quaternion w, x, y, z.
inline constexpr int kPoseDoubles = 7;

/// Adds an object. Followed by `double p_MV[3 * vertex_count]` (x, y, z per vertex, object
/// frame, world units), then `uint32_t triangles[3 * triangle_count]` (vertex indices, counter-
/// clockwise seen from the front), then zero padding to a multiple of 8 bytes.
/// size == AddObjectRecordSize(vertex_count, triangle_count).
struct AddObjectRecord {
  RecordHeader header;        ///< type kAddObject
  uint32_t object_id;         ///< any uint32, not alive in the session
  uint32_t motion;            ///< WireMotion
  uint32_t vertex_count;      ///< >= 1, <= the session's vertex limit
  uint32_t triangle_count;    ///< >= 1, <= the session's triangle limit
  double X_WO[kPoseDoubles];  ///< initial pose, see kPoseDoubles
};
static_assert(sizeof(AddObjectRecord) == 88);
static_assert(offsetof(AddObjectRecord, object_id) == 16);
static_assert(offsetof(AddObjectRecord, motion) == 20);
static_assert(offsetof(AddObjectRecord, vertex_count) == 24);
static_assert(offsetof(AddObjectRecord, triangle_count) == 28);
static_assert(offsetof(AddObjectRecord, X_WO) == 32);

/// Removes an object.
struct RemoveObjectRecord {
  RecordHeader header;  ///< type kRemoveObject, size 24
  uint32_t object_id;   ///< alive in the session
  uint32_t reserved;    ///< zero
};
static_assert(sizeof(RemoveObjectRecord) == 24);
static_assert(offsetof(RemoveObjectRecord, object_id) == 16);
static_assert(offsetof(RemoveObjectRecord, reserved) == 20);

/// Sets the pose of a rigid or deformable object.
struct SetPoseRecord {
  RecordHeader header;        ///< type kSetPose, size 80
  uint32_t object_id;         ///< alive, not static
  uint32_t reserved;          ///< zero
  double X_WO[kPoseDoubles];  ///< see kPoseDoubles
};
static_assert(sizeof(SetPoseRecord) == 80);
static_assert(offsetof(SetPoseRecord, object_id) == 16);
static_assert(offsetof(SetPoseRecord, reserved) == 20);
static_assert(offsetof(SetPoseRecord, X_WO) == 24);

/// Replaces the vertex positions of a deformable object (same count, triangles unchanged).
/// Followed by `double p_MV[3 * vertex_count]`. size == SetVerticesRecordSize(vertex_count).
struct SetVerticesRecord {
  RecordHeader header;    ///< type kSetVertices
  uint32_t object_id;     ///< alive, deformable
  uint32_t vertex_count;  ///< the object's vertex count
};
static_assert(sizeof(SetVerticesRecord) == 24);
static_assert(offsetof(SetVerticesRecord, object_id) == 16);
static_assert(offsetof(SetVerticesRecord, vertex_count) == 20);

/// A full step reply in the reply ring. Followed by `payload_size` bytes: the LCM encoding
/// of a far_lcm::step_reply_t, then zero padding to a multiple of 8 bytes.
struct StepReplyRecord {
  RecordHeader header;    ///< type kStepReply
  uint64_t payload_size;  ///< bytes of the encoded step_reply_t
};
static_assert(sizeof(StepReplyRecord) == 24);
static_assert(offsetof(StepReplyRecord, payload_size) == 16);

/// Rounds `bytes` up to a multiple of kRecordAlignment.
constexpr uint64_t AlignRecordSize(uint64_t bytes) {
  return (bytes + kRecordAlignment - 1) / kRecordAlignment * kRecordAlignment;
}
/// Record sizes in bytes, computed in 64 bits (no overflow for any uint32 counts).
constexpr uint64_t AddObjectRecordSize(uint64_t vertex_count, uint64_t triangle_count) {
  return AlignRecordSize(sizeof(AddObjectRecord) + 24 * vertex_count + 12 * triangle_count);
}
constexpr uint64_t SetVerticesRecordSize(uint64_t vertex_count) {
  return AlignRecordSize(sizeof(SetVerticesRecord) + 24 * vertex_count);
}
constexpr uint64_t StepReplyRecordSize(uint64_t payload_size) {
  return AlignRecordSize(sizeof(StepReplyRecord) + payload_size);
}

/// Where the rings of a segment are. The segment is: header (padded to kRingAlignment),
/// update ring, reply ring.
struct SegmentLayout {
  uint64_t segment_size = 0;
  uint64_t update_ring_offset = 0;
  uint64_t update_ring_capacity = 0;
  uint64_t reply_ring_offset = 0;
  uint64_t reply_ring_capacity = 0;
};

/// Returns the layout for two ring capacities. @pre both are valid capacities
/// (IsValidRingCapacity).
constexpr SegmentLayout MakeSegmentLayout(uint64_t update_capacity, uint64_t reply_capacity) {
  SegmentLayout layout;
  layout.update_ring_offset = kRingAlignment;
  layout.update_ring_capacity = update_capacity;
  layout.reply_ring_offset = kRingAlignment + update_capacity;
  layout.reply_ring_capacity = reply_capacity;
  layout.segment_size = layout.reply_ring_offset + reply_capacity;
  return layout;
}

/// True when `capacity` is a power of two in [kMinRingCapacity, kMaxRingCapacity].
constexpr bool IsValidRingCapacity(uint64_t capacity) {
  return capacity >= kMinRingCapacity && capacity <= kMaxRingCapacity &&
         (capacity & (capacity - 1)) == 0;
}

}  // namespace far::protocol
