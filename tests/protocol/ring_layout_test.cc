// Pins the binary layout of the shared-memory segment (ring_layout.h): a client built from
// another checkout must agree on every byte. Any change here needs a kLayoutVersion bump.

#include "far/protocol/ring_layout.h"

#include <cstddef>
#include <cstring>

#include <gtest/gtest.h>

namespace far::protocol {
namespace {

TEST(RingLayoutTest, MagicIsFarringInMemoryOrder) {
  char bytes[8];
  std::memcpy(bytes, &kSegmentMagic, sizeof(bytes));
  EXPECT_EQ(std::memcmp(bytes, "FARRING\0", 8), 0);
  EXPECT_EQ(kLayoutVersion, 1u);
}

TEST(RingLayoutTest, SegmentHeaderIsPinned) {
  EXPECT_EQ(sizeof(SegmentHeader), 384u);
  EXPECT_EQ(alignof(SegmentHeader), 64u);
  EXPECT_EQ(offsetof(SegmentHeader, magic), 0u);
  EXPECT_EQ(offsetof(SegmentHeader, layout_version), 8u);
  EXPECT_EQ(offsetof(SegmentHeader, header_size), 12u);
  EXPECT_EQ(offsetof(SegmentHeader, segment_size), 16u);
  EXPECT_EQ(offsetof(SegmentHeader, session_id), 24u);
  EXPECT_EQ(offsetof(SegmentHeader, update_ring_offset), 32u);
  EXPECT_EQ(offsetof(SegmentHeader, update_ring_capacity), 40u);
  EXPECT_EQ(offsetof(SegmentHeader, reply_ring_offset), 48u);
  EXPECT_EQ(offsetof(SegmentHeader, reply_ring_capacity), 56u);
  EXPECT_EQ(offsetof(SegmentHeader, session_key), 64u);
  EXPECT_EQ(offsetof(SegmentHeader, reserved), 96u);
  EXPECT_EQ(offsetof(SegmentHeader, update_write_index), 128u);
  EXPECT_EQ(offsetof(SegmentHeader, update_read_index), 192u);
  EXPECT_EQ(offsetof(SegmentHeader, reply_write_index), 256u);
  EXPECT_EQ(offsetof(SegmentHeader, reply_read_index), 320u);
  EXPECT_TRUE(std::atomic<uint64_t>::is_always_lock_free);
}

TEST(RingLayoutTest, RecordsArePinned) {
  EXPECT_EQ(sizeof(RecordHeader), 16u);
  EXPECT_EQ(offsetof(RecordHeader, type), 0u);
  EXPECT_EQ(offsetof(RecordHeader, size), 4u);
  EXPECT_EQ(offsetof(RecordHeader, sequence), 8u);

  EXPECT_EQ(sizeof(AddObjectRecord), 88u);
  EXPECT_EQ(offsetof(AddObjectRecord, object_id), 16u);
  EXPECT_EQ(offsetof(AddObjectRecord, motion), 20u);
  EXPECT_EQ(offsetof(AddObjectRecord, vertex_count), 24u);
  EXPECT_EQ(offsetof(AddObjectRecord, triangle_count), 28u);
  EXPECT_EQ(offsetof(AddObjectRecord, X_WO), 32u);

  EXPECT_EQ(sizeof(RemoveObjectRecord), 24u);
  EXPECT_EQ(offsetof(RemoveObjectRecord, object_id), 16u);
  EXPECT_EQ(offsetof(RemoveObjectRecord, reserved), 20u);

  EXPECT_EQ(sizeof(SetPoseRecord), 80u);
  EXPECT_EQ(offsetof(SetPoseRecord, object_id), 16u);
  EXPECT_EQ(offsetof(SetPoseRecord, reserved), 20u);
  EXPECT_EQ(offsetof(SetPoseRecord, X_WO), 24u);

  EXPECT_EQ(sizeof(SetVerticesRecord), 24u);
  EXPECT_EQ(offsetof(SetVerticesRecord, object_id), 16u);
  EXPECT_EQ(offsetof(SetVerticesRecord, vertex_count), 20u);

  EXPECT_EQ(sizeof(StepReplyRecord), 24u);
  EXPECT_EQ(offsetof(StepReplyRecord, payload_size), 16u);
}

TEST(RingLayoutTest, RecordTypeValuesArePinned) {
  EXPECT_EQ(static_cast<uint32_t>(RecordType::kAddObject), 1u);
  EXPECT_EQ(static_cast<uint32_t>(RecordType::kRemoveObject), 2u);
  EXPECT_EQ(static_cast<uint32_t>(RecordType::kSetPose), 3u);
  EXPECT_EQ(static_cast<uint32_t>(RecordType::kSetVertices), 4u);
  EXPECT_EQ(static_cast<uint32_t>(RecordType::kStepReply), 16u);
  EXPECT_EQ(static_cast<uint32_t>(WireMotion::kStatic), 0u);
  EXPECT_EQ(static_cast<uint32_t>(WireMotion::kRigid), 1u);
  EXPECT_EQ(static_cast<uint32_t>(WireMotion::kDeformable), 2u);
}

TEST(RingLayoutTest, RecordSizesUse64BitArithmeticAndAlignTo8) {
  EXPECT_EQ(AddObjectRecordSize(3, 1), 88u + 72u + 12u + 4u);  // 176, padded from 172
  EXPECT_EQ(AddObjectRecordSize(3, 2), 88u + 72u + 24u);
  EXPECT_EQ(SetVerticesRecordSize(2), 24u + 48u);
  EXPECT_EQ(StepReplyRecordSize(1), 32u);
  // The largest uint32 counts do not overflow.
  EXPECT_EQ(AddObjectRecordSize(0xffffffffu, 0xffffffffu),
            AlignRecordSize(88 + 36 * uint64_t{0xffffffffu}));
  EXPECT_GT(AddObjectRecordSize(0xffffffffu, 0xffffffffu), uint64_t{0xffffffffu});
}

TEST(RingLayoutTest, SegmentLayoutPutsRingsOnPagesAfterTheHeader) {
  const SegmentLayout layout = MakeSegmentLayout(1 << 16, 1 << 17);
  EXPECT_EQ(layout.update_ring_offset, 4096u);
  EXPECT_EQ(layout.update_ring_capacity, 65536u);
  EXPECT_EQ(layout.reply_ring_offset, 4096u + 65536u);
  EXPECT_EQ(layout.reply_ring_capacity, 131072u);
  EXPECT_EQ(layout.segment_size, 4096u + 65536u + 131072u);
  EXPECT_TRUE(IsValidRingCapacity(1 << 16));
  EXPECT_FALSE(IsValidRingCapacity(1 << 15));
  EXPECT_FALSE(IsValidRingCapacity((1 << 16) + 8));
  EXPECT_FALSE(IsValidRingCapacity(uint64_t{1} << 31));
}

}  // namespace
}  // namespace far::protocol
