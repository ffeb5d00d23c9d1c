// DecodeMessage: the byte-level gate every client message passes (cap, fingerprint, schema
// pre-scan, LCM decode, protocol version).

#include "far/protocol/message.h"

#include <cstring>
#include <random>
#include <vector>

#include "test_messages.h"
#include <gtest/gtest.h>

namespace far::protocol {
namespace {

using testing::SampleError;
using testing::SampleOpenSession;
using testing::SampleOpenSessionReply;
using testing::SampleSealed;
using testing::SampleStatusReply;
using testing::SampleStatusRequest;
using testing::SampleStepReply;
using testing::SampleStepRequest;
using testing::SampleStepStatus;

template <typename T>
std::vector<uint8_t> Encode(const T& message) {
  auto bytes = EncodeMessage(message);
  EXPECT_TRUE(bytes);
  return bytes ? *bytes : std::vector<uint8_t>{};
}

void PutBigEndian32(std::vector<uint8_t>& bytes, size_t offset, uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<uint8_t>(value >> (24 - 8 * i));
}

// Offset of the first occurrence of `needle` in `bytes`.
size_t Find(const std::vector<uint8_t>& bytes, const std::vector<uint8_t>& needle) {
  auto it = std::search(bytes.begin(), bytes.end(), needle.begin(), needle.end());
  EXPECT_NE(it, bytes.end());
  return static_cast<size_t>(it - bytes.begin());
}

template <typename T>
void ExpectDecodeError(const std::vector<uint8_t>& bytes, ErrorCode code,
                       const std::string& substring, size_t cap = kMaxStepReplyBytes) {
  auto decoded = DecodeMessage<T>(bytes.data(), bytes.size(), cap);
  ASSERT_FALSE(decoded) << "accepted; expected " << substring;
  EXPECT_EQ(decoded.error().code, code) << decoded.error().message;
  EXPECT_NE(decoded.error().message.find(substring), std::string::npos) << decoded.error().message;
}

// Round trip: the pre-scan must accept exactly the encoding of every filled-in message; a
// schema that drifted from the .lcm file fails here.
template <typename T>
void ExpectRoundTrip(const T& message, MessageType type) {
  const auto bytes = Encode(message);
  auto kind = IdentifyMessage(bytes.data(), bytes.size());
  ASSERT_TRUE(kind) << kind.error().message;
  EXPECT_EQ(*kind, type);
  auto decoded = DecodeMessage<T>(bytes.data(), bytes.size(), kMaxStepReplyBytes);
  ASSERT_TRUE(decoded) << ToString(type) << ": " << decoded.error().message;
  EXPECT_EQ(Encode(*decoded), bytes) << ToString(type);
}

TEST(MessageTest, EveryTypeRoundTripsThroughThePreScan) {
  ExpectRoundTrip(SampleOpenSession(), MessageType::kOpenSession);
  ExpectRoundTrip(SampleOpenSessionReply(), MessageType::kOpenSessionReply);
  ExpectRoundTrip(SampleSealed(), MessageType::kSealed);
  ExpectRoundTrip(SampleStepStatus(), MessageType::kStepStatus);
  ExpectRoundTrip(SampleStepRequest(), MessageType::kStepRequest);
  ExpectRoundTrip(SampleStepReply(), MessageType::kStepReply);
  ExpectRoundTrip(SampleError(), MessageType::kError);
  ExpectRoundTrip(SampleStatusRequest(), MessageType::kStatusRequest);
  ExpectRoundTrip(SampleStatusReply(), MessageType::kStatusReply);
  ExpectRoundTrip(testing::SampleRecordingHeader(), MessageType::kRecordingHeader);
  ExpectRoundTrip(testing::SampleRingRecord(), MessageType::kRingRecord);
}

TEST(MessageTest, FingerprintsArePinned) {
  // The wire contract of protocol version 5 (5: what a cluster needs in the status; 4: contact
  // geometry). A change of any .lcm file
  // changes its fingerprint and fails here: update the value, docs/protocol.md, and
  // kProtocolVersion if the meaning changed, so that old and new peers reject each other with a
  // clear error.
  EXPECT_EQ(far_lcm::open_session_t::getHash(), static_cast<int64_t>(0xfd44631e0fd969b1ull));
  EXPECT_EQ(far_lcm::open_session_reply_t::getHash(), static_cast<int64_t>(0x133fbd56d0df8f90ull));
  EXPECT_EQ(far_lcm::sealed_t::getHash(), static_cast<int64_t>(0x71e71b1583d17514ull));
  EXPECT_EQ(far_lcm::step_status_t::getHash(), static_cast<int64_t>(0x90548ca9dd3567d6ull));
  EXPECT_EQ(far_lcm::step_request_t::getHash(), static_cast<int64_t>(0x7e829d821c8e84edull));
  EXPECT_EQ(far_lcm::step_reply_t::getHash(), static_cast<int64_t>(0x5bd75aad5eeeda94ull));
  EXPECT_EQ(far_lcm::error_t::getHash(), static_cast<int64_t>(0xb22a7284ae722a4full));
  EXPECT_EQ(far_lcm::status_request_t::getHash(), static_cast<int64_t>(0x232a6c3597e1b397ull));
  EXPECT_EQ(far_lcm::status_reply_t::getHash(), static_cast<int64_t>(0xfa43055c3d7de49full));
  EXPECT_EQ(kProtocolVersion, 5);
}

TEST(MessageTest, EmptyArraysAndStringsRoundTrip) {
  far_lcm::step_reply_t reply = SampleStepReply();
  reply = far_lcm::step_reply_t{};
  reply.protocol_version = kProtocolVersion;
  ExpectRoundTrip(reply, MessageType::kStepReply);
}

TEST(MessageTest, IdentifyRejectsShortAndUnknownMessages) {
  const uint8_t four[4] = {1, 2, 3, 4};
  auto short_message = IdentifyMessage(four, sizeof(four));
  ASSERT_FALSE(short_message);
  EXPECT_EQ(short_message.error().code, ErrorCode::kParseError);
  const uint8_t unknown[8] = {0xde, 0xad, 0xbe, 0xef, 0, 0, 0, 1};
  auto not_ours = IdentifyMessage(unknown, sizeof(unknown));
  ASSERT_FALSE(not_ours);
  EXPECT_NE(not_ours.error().message.find("fingerprint 0xdeadbeef00000001 is not a far_lcm type"),
            std::string::npos);
}

TEST(MessageTest, RejectsOversizeBeforeReadingAnyByte) {
  // A null pointer with a huge size: the cap is checked before the bytes are touched.
  auto decoded =
      DecodeMessage<far_lcm::step_request_t>(nullptr, size_t{1} << 30, kMaxControlMessageBytes);
  ASSERT_FALSE(decoded);
  EXPECT_EQ(decoded.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(
      decoded.error().message.find("step_request_t: 1073741824 bytes is over the 4096-byte cap"),
      std::string::npos)
      << decoded.error().message;
  const auto bytes = Encode(SampleStepReply());
  ExpectDecodeError<far_lcm::step_reply_t>(bytes, ErrorCode::kLimitExceeded, "-byte cap",
                                           bytes.size() - 1);
}

template <typename T>
void ExpectEveryPrefixRejected(const T& message) {
  const auto bytes = Encode(message);
  for (size_t size = 0; size < bytes.size(); ++size) {
    const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(size));
    auto decoded = DecodeMessage<T>(prefix.data(), prefix.size(), kMaxStepReplyBytes);
    ASSERT_FALSE(decoded) << "accepted a " << size << "-byte prefix";
    EXPECT_EQ(decoded.error().code, ErrorCode::kParseError) << decoded.error().message;
  }
}

TEST(MessageTest, RejectsEveryTruncation) {
  ExpectEveryPrefixRejected(SampleStepRequest());
  ExpectEveryPrefixRejected(SampleStepReply());
  ExpectEveryPrefixRejected(SampleStatusReply());
  ExpectEveryPrefixRejected(SampleSealed());
  const auto bytes = Encode(SampleStepRequest());
  ExpectDecodeError<far_lcm::step_request_t>(
      std::vector<uint8_t>(bytes.begin(), bytes.end() - 3), ErrorCode::kParseError,
      "step_request_t.timeout_ms: needs 4 bytes, 1 left (truncated)");
}

TEST(MessageTest, RejectsTrailingBytes) {
  auto bytes = Encode(SampleStepRequest());
  bytes.push_back(0);
  ExpectDecodeError<far_lcm::step_request_t>(
      bytes, ErrorCode::kParseError, "step_request_t: 1 trailing bytes after the last field");
}

TEST(MessageTest, RejectsWrongFingerprint) {
  const auto bytes = Encode(SampleStepStatus());
  ExpectDecodeError<far_lcm::step_request_t>(bytes, ErrorCode::kParseError,
                                             "does not match step_request_t's");
}

TEST(MessageTest, RejectsWrongProtocolVersion) {
  auto message = SampleStepRequest();
  message.protocol_version = kProtocolVersion + 1;
  ExpectDecodeError<far_lcm::step_request_t>(Encode(message), ErrorCode::kVersionMismatch,
                                             "step_request_t.protocol_version: got 6, expected 5");
}

TEST(MessageTest, RejectsAForgedHugeArrayLengthWithoutAllocating) {
  // A small message that claims 2^31 - 1 object ids: LCM's decode would resize a vector to
  // 16 GiB before noticing the bytes are not there.
  auto message = SampleStepReply();
  message.num_pcs_objects = 1;
  message.pcs_objects = {0x5A5A5A5A};
  auto bytes = Encode(message);
  const size_t at = Find(bytes, {0, 0, 0, 1, 0, 0, 0, 0, 0x5A, 0x5A, 0x5A, 0x5A});
  PutBigEndian32(bytes, at, 0x7FFFFFFF);
  ExpectDecodeError<far_lcm::step_reply_t>(
      bytes, ErrorCode::kParseError,
      "step_reply_t.pcs_objects: 2147483647 elements of 8 bytes need 17179869176 bytes");
  ExpectDecodeError<far_lcm::step_reply_t>(bytes, ErrorCode::kParseError,
                                           "(num_pcs_objects is too large)");
}

TEST(MessageTest, RejectsNegativeCountsThatWouldMakeLcmThrow) {
  auto message = SampleStepReply();
  message.num_pcs_objects = 1;
  message.pcs_objects = {0x5A5A5A5A};
  auto bytes = Encode(message);
  PutBigEndian32(bytes, Find(bytes, {0, 0, 0, 1, 0, 0, 0, 0, 0x5A, 0x5A, 0x5A, 0x5A}), 0xFFFFFFFF);
  // What the pre-scan protects against: LCM 1.3.1's decode resizes to size_t(-1) and throws.
  far_lcm::step_reply_t raw;
  EXPECT_ANY_THROW(raw.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  ExpectDecodeError<far_lcm::step_reply_t>(bytes, ErrorCode::kParseError,
                                           "step_reply_t.num_pcs_objects: -1 is negative");
}

TEST(MessageTest, RejectsHugeStringArrayCounts) {
  auto message = SampleStatusReply();
  auto bytes = Encode(message);
  // num_sessions (2) is followed by session_id[0] == 3 as int64.
  const size_t at = Find(bytes, {0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 3});
  PutBigEndian32(bytes, at, 0x40000000);
  ExpectDecodeError<far_lcm::status_reply_t>(bytes, ErrorCode::kParseError,
                                             "status_reply_t.session_id: 1073741824 elements");
}

TEST(MessageTest, RejectsMalformedStrings) {
  auto message = SampleStepRequest();
  message.method = "far";
  const auto good = Encode(message);
  // "far" is encoded as length 4, 'f', 'a', 'r', 0.
  const size_t at = Find(good, {0, 0, 0, 4, 'f', 'a', 'r', 0});

  auto zero = good;
  PutBigEndian32(zero, at, 0);
  ExpectDecodeError<far_lcm::step_request_t>(
      zero, ErrorCode::kParseError,
      "step_request_t.method: string length 0 is less than 1 (LCM strings include their NUL)");

  auto negative = good;
  PutBigEndian32(negative, at, 0x80000000);
  ExpectDecodeError<far_lcm::step_request_t>(negative, ErrorCode::kParseError,
                                             "string length -2147483648 is less than 1");

  auto huge = good;
  PutBigEndian32(huge, at, 0x7FFFFFFF);
  ExpectDecodeError<far_lcm::step_request_t>(huge, ErrorCode::kParseError,
                                             "string length 2147483647 runs past the end");

  auto no_nul = good;
  no_nul[at + 7] = 'x';
  ExpectDecodeError<far_lcm::step_request_t>(no_nul, ErrorCode::kParseError,
                                             "step_request_t.method: string lacks its final NUL");

  auto inner_nul = good;
  inner_nul[at + 5] = 0;
  ExpectDecodeError<far_lcm::step_request_t>(inner_nul, ErrorCode::kParseError,
                                             "step_request_t.method: string contains a NUL");
}

TEST(MessageTest, SurvivesGarbageAndMutations) {
  // Random bytes behind a valid fingerprint, and random mutations of a valid reply: every
  // outcome is an error or a message whose arrays fit in its bytes; nothing throws or crashes.
  std::mt19937 random(12345);
  const auto reply = Encode(SampleStepReply());
  int accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    std::vector<uint8_t> bytes;
    if (i % 2 == 0) {
      bytes.resize(8 + random() % 300);
      for (auto& b : bytes) b = static_cast<uint8_t>(random());
      std::copy(reply.begin(), reply.begin() + 8, bytes.begin());
    } else {
      bytes = reply;
      const int flips = 1 + static_cast<int>(random() % 4);
      for (int k = 0; k < flips; ++k)
        bytes[random() % bytes.size()] = static_cast<uint8_t>(random());
    }
    auto decoded =
        DecodeMessage<far_lcm::step_reply_t>(bytes.data(), bytes.size(), kMaxStepReplyBytes);
    if (decoded) {
      ++accepted;
      EXPECT_LE(decoded->pcs_objects.size() * 4, bytes.size());
      EXPECT_LE(decoded->contact_object_a.size() * 4, bytes.size());
    }
  }
  EXPECT_GT(accepted, 0);  // mutations of values only (e.g. ids) decode fine
}

}  // namespace
}  // namespace far::protocol
