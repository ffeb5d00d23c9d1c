// RingWriter / RingReader: framing, wrap-around, back-pressure, and a producer that lies.

#include "far/protocol/ring.h"

#include <atomic>
#include <cstring>
#include <thread>
#include <vector>

#include "test_ring.h"
#include <gtest/gtest.h>

namespace far::protocol {
namespace {

using testing::TestRing;

std::vector<uint8_t> Pattern(size_t size, uint8_t seed) {
  std::vector<uint8_t> bytes(size);
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<uint8_t>(seed + 7 * i);
  return bytes;
}

std::vector<uint8_t> BodyOf(const RawRecord& record) {
  return {record.bytes.begin() + sizeof(RecordHeader), record.bytes.end()};
}

TEST(RingTest, RoundTripsRecordsInOrder) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto a = Pattern(8, 1);
  const auto b = Pattern(24, 2);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {a}));
  ASSERT_TRUE(writer.Write(RecordType::kRemoveObject, {b, a}));
  EXPECT_EQ(writer.last_sequence(), 2u);
  EXPECT_EQ(ring.write_index.load(), 24u + 48u);

  auto records = reader.ReadUpTo(2);
  ASSERT_TRUE(records) << records.error().message;
  ASSERT_EQ(records->size(), 2u);
  EXPECT_EQ((*records)[0].header.sequence, 1u);
  EXPECT_EQ((*records)[0].header.type, static_cast<uint32_t>(RecordType::kSetPose));
  EXPECT_EQ((*records)[0].header.size, 24u);
  EXPECT_EQ(BodyOf((*records)[0]), a);
  EXPECT_EQ((*records)[1].index, 24u);
  std::vector<uint8_t> ba = b;
  ba.insert(ba.end(), a.begin(), a.end());
  EXPECT_EQ(BodyOf((*records)[1]), ba);
  EXPECT_EQ(reader.last_sequence(), 2u);
  EXPECT_EQ(ring.read_index.load(), 72u);  // published: the space is free again
  // Asking again for what was read returns nothing.
  auto again = reader.ReadUpTo(2);
  ASSERT_TRUE(again);
  EXPECT_TRUE(again->empty());
}

TEST(RingTest, PadsRecordsWithZerosToMultiplesOf8) {
  TestRing ring(256);
  std::fill(ring.data.begin(), ring.data.end(), 0xAB);
  RingWriter writer(ring.region());
  const uint8_t three[3] = {1, 2, 3};
  auto position = writer.Write(RecordType::kSetPose, {three});
  ASSERT_TRUE(position);
  EXPECT_EQ(position->size, 24u);
  for (size_t i = 19; i < 24; ++i) EXPECT_EQ(ring.data[i], 0) << i;
}

TEST(RingTest, RecordsWrapAroundTheEndIntact) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  int wrapped = 0;
  for (int i = 0; i < 200; ++i) {
    const auto body = Pattern(8 + (i * 37) % 150, static_cast<uint8_t>(i));
    auto position = writer.Write(RecordType::kSetVertices, {body});
    ASSERT_TRUE(position) << i << ": " << position.error().message;
    if ((position->index & 255) + position->size > 256) ++wrapped;
    auto records = reader.ReadUpTo(writer.last_sequence());
    ASSERT_TRUE(records) << records.error().message;
    ASSERT_EQ(records->size(), 1u);
    const std::vector<uint8_t> got = BodyOf((*records)[0]);
    ASSERT_GE(got.size(), body.size());
    EXPECT_TRUE(std::equal(body.begin(), body.end(), got.begin())) << i;
    EXPECT_EQ((*records)[0].header.sequence, static_cast<uint64_t>(i + 1));
  }
  EXPECT_GT(wrapped, 10);  // the test exercised wrap-around, headers included
}

TEST(RingTest, WriterReportsBusyWhenFullAndNeverBlocks) {
  TestRing ring(128);
  RingWriter writer(ring.region());
  const auto body = Pattern(48, 0);  // 64-byte records
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  auto full = writer.Write(RecordType::kSetPose, {body});
  ASSERT_FALSE(full);
  EXPECT_EQ(full.error().code, ErrorCode::kBusy);
  EXPECT_NE(full.error().message.find("64 bytes needed, 0 free"), std::string::npos)
      << full.error().message;
  auto waited = writer.WriteWait(RecordType::kSetPose, {body}, std::chrono::milliseconds(5));
  ASSERT_FALSE(waited);
  EXPECT_EQ(waited.error().code, ErrorCode::kTimeout);
}

TEST(RingTest, WriteWaitSucceedsWhenTheConsumerFreesSpace) {
  TestRing ring(128);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 128);
  const auto body = Pattern(48, 0);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  std::thread consumer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_TRUE(reader.ReadUpTo(1));
  });
  auto waited = writer.WriteWait(RecordType::kSetPose, {body}, std::chrono::seconds(5));
  consumer.join();
  ASSERT_TRUE(waited) << waited.error().message;
  EXPECT_EQ(waited->sequence, 3u);
}

TEST(RingTest, RecordLargerThanTheRingIsLimitExceeded) {
  TestRing ring(128);
  RingWriter writer(ring.region());
  const auto body = Pattern(120, 0);
  auto written = writer.Write(RecordType::kSetPose, {body});
  ASSERT_FALSE(written);
  EXPECT_EQ(written.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(written.error().message.find("larger than the ring"), std::string::npos);
}

TEST(RingTest, ProducerAndConsumerThreadsAgreeOnEveryRecord) {
  TestRing ring(1024);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 1024);
  constexpr int kRecords = 20000;
  std::thread producer([&] {
    for (int i = 0; i < kRecords; ++i) {
      const auto body = Pattern(8 + (i % 13) * 8, static_cast<uint8_t>(i));
      ASSERT_TRUE(writer.WriteWait(RecordType::kSetPose, {body}, std::chrono::seconds(10)));
    }
  });
  int received = 0;
  while (received < kRecords) {
    auto next = reader.ReadNext();
    ASSERT_TRUE(next) << next.error().message;
    if (!next->has_value()) {
      std::this_thread::yield();
      continue;
    }
    const auto expected = Pattern(8 + (received % 13) * 8, static_cast<uint8_t>(received));
    ASSERT_EQ(BodyOf(**next), expected) << received;
    ++received;
  }
  producer.join();
  EXPECT_EQ(reader.last_sequence(), static_cast<uint64_t>(kRecords));
}

// ---- a hostile producer ----------------------------------------------------------------------

void ExpectCorrupt(RingReader& reader, uint64_t up_to, const std::string& substring) {
  auto records = reader.ReadUpTo(up_to);
  ASSERT_FALSE(records);
  EXPECT_EQ(records.error().code, ErrorCode::kParseError);
  EXPECT_NE(records.error().message.find(substring), std::string::npos) << records.error().message;
  EXPECT_TRUE(reader.corrupt());
  // Sticky: the same error again, and nothing published.
  auto again = reader.ReadNext();
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error().message, records.error().message);
}

TEST(RingReaderTest, RejectsTruncatedHeader) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 24, 1);
  ring.write_index = 8;  // half a header committed
  ExpectCorrupt(reader, 1, "only 8 bytes committed");
  EXPECT_EQ(ring.read_index.load(), 0u);
}

TEST(RingReaderTest, RejectsSizeSmallerThanHeader) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 8, 1);
  ring.write_index = 24;
  ExpectCorrupt(reader, 1, "size 8 is smaller than the 16-byte record header");
}

TEST(RingReaderTest, RejectsSizeNotMultipleOf8) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 20, 1);
  ring.write_index = 24;
  ExpectCorrupt(reader, 1, "size 20 is not a multiple of 8");
}

TEST(RingReaderTest, RejectsSizePastTheCommittedEnd) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 0xFFFFFFF8u, 1);
  ring.write_index = 32;
  ExpectCorrupt(reader, 1, "size 4294967288 runs past the end of the committed data (32 bytes)");
}

TEST(RingReaderTest, RejectsRecordOverTheRecordLimit) {
  TestRing ring(256);
  RingReader reader(ring.region(), 64);
  ring.PokeHeader(0, 3, 128, 1);
  ring.write_index = 128;
  auto records = reader.ReadUpTo(1);
  ASSERT_FALSE(records);
  EXPECT_EQ(records.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(records.error().message.find("over the 64-byte record limit"), std::string::npos);
  EXPECT_TRUE(reader.corrupt());
}

TEST(RingReaderTest, RejectsSequenceOutOfOrder) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 24, 1);
  ring.PokeHeader(24, 3, 24, 7);
  ring.write_index = 48;
  ExpectCorrupt(reader, 2, "record 2 at index 24: sequence 7 is out of order (expected 2)");
}

TEST(RingReaderTest, RejectsWriteIndexGoingBackwards) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(8, 0);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(reader.ReadUpTo(2));
  ring.write_index = 24;  // the producer lies: 48 -> 24
  ExpectCorrupt(reader, 3, "write_index 24 went backwards (read index 48)");
}

TEST(RingReaderTest, RejectsWriteIndexMoreThanACapacityAhead) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  ring.PokeHeader(0, 3, 24, 1);
  ring.write_index = 256 + 8;
  ExpectCorrupt(reader, 1, "write_index 264 is more than the capacity 256 ahead of read index 0");
}

TEST(RingReaderTest, CommitBeyondWrittenConsumesNothingAndIsNotCorrupt) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(8, 0);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  auto records = reader.ReadUpTo(3);
  ASSERT_FALSE(records);
  EXPECT_EQ(records.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(records.error().message.find("sequence 3 is not committed: the ring holds records up "
                                         "to 1"),
            std::string::npos)
      << records.error().message;
  EXPECT_FALSE(reader.corrupt());
  EXPECT_EQ(reader.last_sequence(), 0u);
  EXPECT_EQ(ring.read_index.load(), 0u);
  // Once written, the same request succeeds.
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  auto later = reader.ReadUpTo(3);
  ASSERT_TRUE(later) << later.error().message;
  EXPECT_EQ(later->size(), 3u);
}

TEST(RingReaderTest, SequenceBeforeLastReadIsInvalidArgument) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(8, 0);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(reader.ReadUpTo(2));
  auto records = reader.ReadUpTo(1);
  ASSERT_FALSE(records);
  EXPECT_EQ(records.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(records.error().message.find("before the last record already read (2)"),
            std::string::npos);
  EXPECT_FALSE(reader.corrupt());
}

TEST(RingReaderTest, HalfWrittenRecordIsInvisibleUntilCommitted) {
  TestRing ring(256);
  RingReader reader(ring.region(), 256);
  // The producer stopped in the middle: bytes written, write_index not advanced.
  ring.PokeHeader(0, 3, 32, 1);
  auto next = reader.ReadNext();
  ASSERT_TRUE(next);
  EXPECT_FALSE(next->has_value());
  auto records = reader.ReadUpTo(1);
  ASSERT_FALSE(records);
  EXPECT_EQ(records.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(reader.corrupt());
}

TEST(RingReaderTest, UsesItsCopyWhenTheProducerOverwritesDuringTheCopy) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(16, 5);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  // Between the header check and the body copy, the producer rewrites the header to claim a
  // huge size and another type: the reader must keep the header it checked.
  reader.SetCopyHookForTesting(
      [&](const RecordHeader&) { ring.PokeHeader(0, 99, 0xFFFFFFF0u, 42); });
  auto records = reader.ReadUpTo(1);
  ASSERT_TRUE(records) << records.error().message;
  const RawRecord& record = (*records)[0];
  EXPECT_EQ(record.header.size, 32u);
  EXPECT_EQ(record.header.type, static_cast<uint32_t>(RecordType::kSetPose));
  RecordHeader in_bytes;
  std::memcpy(&in_bytes, record.bytes.data(), sizeof(in_bytes));
  EXPECT_EQ(in_bytes.size, 32u);
  EXPECT_EQ(in_bytes.type, static_cast<uint32_t>(RecordType::kSetPose));
  EXPECT_EQ(in_bytes.sequence, 1u);
  EXPECT_EQ(record.bytes.size(), 32u);
}

TEST(RingReaderTest, CopiedRecordsDoNotChangeWhenSharedMemoryDoes) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(16, 5);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  auto records = reader.ReadUpTo(1);
  ASSERT_TRUE(records);
  std::fill(ring.data.begin(), ring.data.end(), 0xEE);
  EXPECT_EQ(BodyOf((*records)[0]), body);
}

TEST(RingReaderTest, IgnoresAScribbledReadIndex) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  RingReader reader(ring.region(), 256);
  const auto body = Pattern(8, 0);
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ASSERT_TRUE(reader.ReadUpTo(1));
  ring.read_index = 12345;  // the other side scribbles the consumer's index
  EXPECT_FALSE(writer.Write(RecordType::kSetPose, {body}));  // the writer checks it too
  ring.read_index = 24;                                      // undone for the writer
  ASSERT_TRUE(writer.Write(RecordType::kSetPose, {body}));
  ring.read_index = 999;
  auto records = reader.ReadUpTo(2);
  ASSERT_TRUE(records) << records.error().message;
  EXPECT_EQ((*records)[0].index, 24u);  // the reader's own index, not the scribbled one
}

TEST(RingWriterTest, RejectsAnInconsistentConsumerIndex) {
  TestRing ring(256);
  RingWriter writer(ring.region());
  ring.read_index = 64;  // ahead of the write index 0
  auto written = writer.Write(RecordType::kStepReply, {Pattern(8, 0)});
  ASSERT_FALSE(written);
  EXPECT_EQ(written.error().code, ErrorCode::kParseError);
  EXPECT_NE(written.error().message.find("read index 64 is inconsistent with the write index 0"),
            std::string::npos);
}

}  // namespace
}  // namespace far::protocol
