// Session message authentication: HMAC tags over the encoding, at a fixed offset in every
// session message type.

#include "far/protocol/session_auth.h"

#include <algorithm>
#include <cstring>
#include <set>
#include <string>

#include "test_messages.h"
#include <gtest/gtest.h>

namespace far::protocol {
namespace {

using testing::SampleStepRequest;

template <typename T>
void ExpectAuthAtFixedOffset(T message) {
  std::memset(message.auth, 0xAB, sizeof(message.auth));
  message.session_id = 0x0102030405060708;
  auto bytes = EncodeMessage(message);
  ASSERT_TRUE(bytes);
  for (size_t i = 0; i < kAuthBytes; ++i) EXPECT_EQ((*bytes)[kAuthOffset + i], 0xAB) << i;
  for (size_t i = 0; i < 8; ++i) EXPECT_EQ((*bytes)[12 + i], i + 1);  // big-endian session_id
}

TEST(SessionAuthTest, EverySessionMessageHasAuthAtTheSameOffset) {
  ExpectAuthAtFixedOffset(testing::SampleStepStatus());
  ExpectAuthAtFixedOffset(testing::SampleStepRequest());
  ExpectAuthAtFixedOffset(testing::SampleStepReply());
  ExpectAuthAtFixedOffset(testing::SampleError());
  EXPECT_TRUE(IsSessionMessage(MessageType::kStepRequest));
  EXPECT_TRUE(IsSessionMessage(MessageType::kError));
  EXPECT_FALSE(IsSessionMessage(MessageType::kOpenSession));
  EXPECT_FALSE(IsSessionMessage(MessageType::kStatusReply));
  EXPECT_FALSE(IsSessionMessage(MessageType::kSealed));
}

TEST(SessionAuthTest, SealedMessagesOpenOnlyForTheirSessionAndKey) {
  const SessionKey key = NewSessionKey();
  auto inner = EncodeMessage(testing::SampleStepReply());
  ASSERT_TRUE(inner);
  auto sealed = SealEncoded(*inner, 3, 17, key);
  ASSERT_TRUE(sealed);
  // The inner bytes are not readable in the sealed message.
  const std::string needle = "object_cull";
  EXPECT_EQ(std::search(sealed->begin(), sealed->end(), needle.begin(), needle.end()),
            sealed->end());
  auto opened = OpenSealed(sealed->data(), sealed->size(), 3, key, kMaxStepReplyBytes);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_EQ(opened->request_id, 17);
  EXPECT_EQ(opened->inner, *inner);
  // Another key, another session, or any flipped bit: it does not open.
  EXPECT_EQ(OpenSealed(sealed->data(), sealed->size(), 3, NewSessionKey(), kMaxStepReplyBytes)
                .error()
                .code,
            ErrorCode::kPermissionDenied);
  EXPECT_FALSE(OpenSealed(sealed->data(), sealed->size(), 4, key, kMaxStepReplyBytes));
  for (size_t i = 0; i < sealed->size(); i += 7) {
    auto tampered = *sealed;
    tampered[i] ^= 0x10;
    EXPECT_FALSE(OpenSealed(tampered.data(), tampered.size(), 3, key, kMaxStepReplyBytes))
        << "byte " << i;
  }
}

TEST(SessionAuthTest, ASealedMessagesSequenceCannotBeChanged) {
  const SessionKey key = NewSessionKey();
  auto inner = EncodeMessage(testing::SampleError());
  ASSERT_TRUE(inner);
  auto sealed = SealEncoded(*inner, 3, 17, key);
  ASSERT_TRUE(sealed);
  auto message =
      DecodeMessage<far_lcm::sealed_t>(sealed->data(), sealed->size(), kMaxControlMessageBytes);
  ASSERT_TRUE(message);
  message->request_id = 99;  // a replayed message given a fresh sequence number
  auto forged = EncodeMessage(*message);
  ASSERT_TRUE(forged);
  EXPECT_FALSE(OpenSealed(forged->data(), forged->size(), 3, key, kMaxStepReplyBytes));
}

TEST(SessionAuthTest, SignedMessagesVerifyAndDecode) {
  const SessionKey key = NewSessionKey();
  auto bytes = EncodeSigned(SampleStepRequest(), key);
  ASSERT_TRUE(bytes);
  EXPECT_TRUE(VerifyEncoded(*bytes, key));
  auto decoded =
      DecodeMessage<far_lcm::step_request_t>(bytes->data(), bytes->size(), kMaxControlMessageBytes);
  ASSERT_TRUE(decoded);
  EXPECT_NE(std::memcmp(decoded->auth, std::array<uint8_t, 32>{}.data(), 32), 0);
}

TEST(SessionAuthTest, AnyFlippedBitFailsVerification) {
  const SessionKey key = NewSessionKey();
  auto bytes = EncodeSigned(SampleStepRequest(), key);
  ASSERT_TRUE(bytes);
  for (size_t i = 0; i < bytes->size(); ++i) {
    auto tampered = *bytes;
    tampered[i] ^= 0x01;
    auto ok = VerifyEncoded(tampered, key);
    ASSERT_FALSE(ok) << "byte " << i;
    EXPECT_EQ(ok.error().code, ErrorCode::kPermissionDenied);
    EXPECT_NE(ok.error().message.find("auth: the tag does not match the session key"),
              std::string::npos);
  }
}

TEST(SessionAuthTest, AnotherSessionsKeyFails) {
  auto bytes = EncodeSigned(SampleStepRequest(), NewSessionKey());
  ASSERT_TRUE(bytes);
  EXPECT_FALSE(VerifyEncoded(*bytes, NewSessionKey()));
}

TEST(SessionAuthTest, UnsignedMessagesFail) {
  auto bytes = EncodeMessage(SampleStepRequest());  // auth all zero
  ASSERT_TRUE(bytes);
  SessionKey zero{};
  EXPECT_FALSE(VerifyEncoded(*bytes, NewSessionKey()));
  EXPECT_FALSE(VerifyEncoded(*bytes, zero));
}

TEST(SessionAuthTest, TooShortIsAParseError) {
  const std::vector<uint8_t> bytes(51, 0);
  auto ok = VerifyEncoded(bytes, NewSessionKey());
  ASSERT_FALSE(ok);
  EXPECT_EQ(ok.error().code, ErrorCode::kParseError);
}

TEST(SessionAuthTest, KeysAreRandom) {
  std::set<SessionKey> keys;
  for (int i = 0; i < 100; ++i) keys.insert(NewSessionKey());
  EXPECT_EQ(keys.size(), 100u);
  EXPECT_NE(HashBytes(std::vector<uint8_t>{1}), HashBytes(std::vector<uint8_t>{2}));
}

}  // namespace
}  // namespace far::protocol
