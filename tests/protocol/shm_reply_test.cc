// Large step replies through the reply ring: the daemon's EncodeStepReplyForTransport and the
// client's ReceiveStepReply, directly and over an in-process LCM (memq://, no network).

#include "far/protocol/shm_reply.h"

#include <unistd.h>

#include <cstring>
#include <optional>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/shm_segment.h"

namespace far::protocol {
namespace {

StepResult ContactsResult(int count) {
  StepResult result;
  for (int i = 0; i < count; ++i) {
    result.contacts.push_back({static_cast<uint32_t>(i % 100), static_cast<uint32_t>(i),
                               static_cast<uint32_t>(100 + i % 7), static_cast<uint32_t>(3 * i)});
  }
  result.stats.stages = {{Stage::kExact, 1.5}};
  return result;
}

far_lcm::step_reply_t FullReply(int contacts, int64_t request_id) {
  auto reply =
      MakeStepReply({3, request_id, request_id, 0}, Output::kContacts, ContactsResult(contacts));
  EXPECT_TRUE(reply);
  return *reply;
}

struct Session {
  Session() {
    auto created = ShmSegment::Create(3, {kMinRingCapacity, uint64_t{1} << 22});
    EXPECT_TRUE(created) << created.error().message;
    daemon = std::move(*created);
    auto opened = ShmSegment::Open(dup(daemon->fd()), 3);
    EXPECT_TRUE(opened) << opened.error().message;
    client = std::move(*opened);
    daemon_replies.emplace(daemon->reply_ring());
    client_replies.emplace(client->reply_ring(), kMaxStepReplyBytes);
  }
  std::unique_ptr<ShmSegment> daemon;
  std::unique_ptr<ShmSegment> client;
  std::optional<RingWriter> daemon_replies;
  std::optional<RingReader> client_replies;
  int64_t sequence = 0;

  // The daemon's side: the sealed bytes it publishes for `full`.
  Result<std::vector<uint8_t>> Send(const far_lcm::step_reply_t& full) {
    return EncodeStepReplyForTransport(full, *daemon_replies, daemon->session_key(), ++sequence);
  }
  // The client's side: open the sealed message, then the reply (from the ring for a stub).
  Result<far_lcm::step_reply_t> Receive(const std::vector<uint8_t>& bytes,
                                        const SessionKey* key = nullptr,
                                        SkippedReplies* skipped = nullptr) {
    auto opened = OpenSealed(bytes.data(), bytes.size(), 3, key ? *key : client->session_key(),
                             kMaxStepReplyBytes);
    if (!opened) return opened.error();
    return ReceiveStepReply(opened->inner, *client_replies, skipped);
  }
};

TEST(ShmReplyTest, RepliesThatWouldNeedMoreThanOneDatagramGoThroughTheRing) {
  EXPECT_FALSE(ShouldUseShmReply(0));
  EXPECT_FALSE(ShouldUseShmReply(63 * 1024));
  EXPECT_TRUE(ShouldUseShmReply(63 * 1024 + 1));
  // LCM udpm's single-datagram limit (channel + 1 + payload <= 65499) holds for every inline
  // reply on a session channel.
  // (sealing adds its header, nonce and tag: 64 bytes at most)
  EXPECT_LE(kShmReplyThresholdBytes + 64 +
                SessionReplyChannel("FAR_GPU_1234567890_", INT64_MAX).size() + 1,
            65499u);
}

TEST(ShmReplyTest, SmallRepliesGoInline) {
  Session session;
  const auto full = FullReply(100, 1);
  auto bytes = session.Send(full);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(session.daemon_replies->last_sequence(), 0u);  // nothing in the ring
  auto received = session.Receive(*bytes);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_FALSE(received->reply_in_shm);
  EXPECT_EQ(received->num_contacts, 100);
}

TEST(ShmReplyTest, LargeRepliesGoThroughTheRingWhole) {
  Session session;
  const auto full = FullReply(100000, 1);
  auto bytes = session.Send(full);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_LT(bytes->size(), 640u);  // only the sealed stub travels over LCM
  EXPECT_EQ(session.daemon_replies->last_sequence(), 1u);
  auto received = session.Receive(*bytes);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_FALSE(received->reply_in_shm);
  auto result = ParseStepReply(*received);
  ASSERT_TRUE(result) << result.error().message;
  EXPECT_EQ(result->contacts, ContactsResult(100000).contacts);
  EXPECT_EQ(result->stats.stages.size(), 1u);
}

TEST(ShmReplyTest, SkipsRepliesWhoseStubsWereLost) {
  Session session;
  auto lost = session.Send(FullReply(20000, 1));
  auto kept = session.Send(FullReply(30000, 2));
  ASSERT_TRUE(lost && kept);
  auto received = session.Receive(*kept);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_EQ(received->request_id, 2);
  EXPECT_EQ(received->num_contacts, 30000);
  // The lost one is gone for good: asking for it now is kNotFound.
  auto late = session.Receive(*lost);
  ASSERT_FALSE(late);
  EXPECT_EQ(late.error().code, ErrorCode::kNotFound);
}

// The daemon sends a lost stub again when the client asks for its step again (docs/protocol.md,
// "Lost datagrams"): the record skipped on the way to a later one is still there for it, once.
TEST(ShmReplyTest, AStubSentAgainFindsTheRecordSkippedBeforeIt) {
  Session session;
  SkippedReplies skipped;
  auto lost = session.Send(FullReply(20000, 1));
  auto later = session.Send(FullReply(30000, 2));
  ASSERT_TRUE(lost && later);
  ASSERT_TRUE(session.Receive(*later, nullptr, &skipped));
  // The daemon seals the kept stub again, under a new sequence number.
  auto opened =
      OpenSealed(lost->data(), lost->size(), 3, session.client->session_key(), kMaxStepReplyBytes);
  ASSERT_TRUE(opened);
  auto again = SealEncoded(opened->inner, 3, ++session.sequence, session.daemon->session_key());
  ASSERT_TRUE(again);
  auto received = session.Receive(*again, nullptr, &skipped);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_EQ(received->request_id, 1);
  EXPECT_EQ(received->num_contacts, 20000);
  auto twice = session.Receive(*again, nullptr, &skipped);
  ASSERT_FALSE(twice);
  EXPECT_EQ(twice.error().code, ErrorCode::kNotFound);
}

TEST(ShmReplyTest, ASkippedRecordIsCheckedAgainstItsStubLikeOneInTheRing) {
  Session session;
  SkippedReplies skipped;
  auto lost = session.Send(FullReply(20000, 1));
  auto later = session.Send(FullReply(30000, 2));
  ASSERT_TRUE(lost && later);
  ASSERT_TRUE(session.Receive(*later, nullptr, &skipped));
  auto opened =
      OpenSealed(lost->data(), lost->size(), 3, session.client->session_key(), kMaxStepReplyBytes);
  ASSERT_TRUE(opened);
  auto stub = DecodeMessage<far_lcm::step_reply_t>(opened->inner.data(), opened->inner.size(),
                                                   kMaxStepReplyBytes);
  ASSERT_TRUE(stub);
  ShmReplyRef ref;
  ref.sequence = static_cast<uint64_t>(stub->shm_reply_sequence);
  ref.index = static_cast<uint64_t>(stub->shm_reply_index);
  ref.bytes = static_cast<uint64_t>(stub->shm_reply_bytes);
  std::memcpy(ref.hash.data(), stub->shm_reply_hash, ref.hash.size());
  ref.hash[0] ^= 1;
  auto taken = skipped.Take(ref);
  ASSERT_FALSE(taken);
  EXPECT_EQ(taken.error().code, ErrorCode::kParseError);
  EXPECT_NE(taken.error().message.find("hash differs"), std::string::npos) << taken.error().message;
}

TEST(ShmReplyTest, DetectsAPayloadChangedAfterItWasWritten) {
  Session session;
  auto bytes = session.Send(FullReply(20000, 1));
  ASSERT_TRUE(bytes);
  // Somebody changes one byte of the payload in shared memory.
  RingRegion region = session.client->reply_ring();
  region.data[sizeof(StepReplyRecord) + 1000] ^= 0xFF;
  auto received = session.Receive(*bytes);
  ASSERT_FALSE(received);
  EXPECT_NE(received.error().message.find("the payload's hash differs from the stub's"),
            std::string::npos)
      << received.error().message;
}

TEST(ShmReplyTest, RejectsAStubSealedWithAnotherKey) {
  Session session;
  auto bytes = session.Send(FullReply(20000, 1));
  ASSERT_TRUE(bytes);
  const SessionKey other = NewSessionKey();
  auto received = session.Receive(*bytes, &other);
  ASSERT_FALSE(received);
  EXPECT_EQ(received.error().code, ErrorCode::kPermissionDenied);
  EXPECT_EQ(session.client_replies->last_sequence(), 0u);  // the ring was not touched
}

TEST(ShmReplyTest, FullRingIsBusyUntilTheClientReads) {
  Session session;
  std::vector<std::vector<uint8_t>> stubs;
  // 70k contacts are ~1.7 MB (24 bytes each); the 4 MiB ring holds two.
  for (int i = 0; i < 2; ++i) {
    auto bytes = session.Send(FullReply(70000, i + 1));
    ASSERT_TRUE(bytes) << bytes.error().message;
    stubs.push_back(*bytes);
  }
  auto third = session.Send(FullReply(70000, 3));
  ASSERT_FALSE(third);
  EXPECT_EQ(third.error().code, ErrorCode::kBusy);
  ASSERT_TRUE(session.Receive(stubs[0]));
  EXPECT_TRUE(session.Send(FullReply(70000, 3)));
}

// The whole path over LCM, in process: memq:// never touches the network. Subscribed through
// the C API: GCC 12's -fsanitize=vptr miscompiles the pointer-to-member call in lcm-cpp's
// subscription callbacks (the asan preset would crash here; docs/protocol.md).
struct RawReceiver {
  static void Handle(const lcm_recv_buf_t* buffer, const char* channel, void* user) {
    auto* self = static_cast<RawReceiver*>(user);
    const auto* data = static_cast<const uint8_t*>(buffer->data);
    self->messages.emplace_back(data, data + buffer->data_size);
    self->channels.emplace_back(channel);
  }
  std::vector<std::vector<uint8_t>> messages;
  std::vector<std::string> channels;
};

TEST(ShmReplyTest, WorksOverLcmMemq) {
  Session session;
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  RawReceiver receiver;
  const std::string channel = SessionReplyChannel("FAR_", 3);
  lcm_subscribe(lcm.getUnderlyingLCM(), channel.c_str(), &RawReceiver::Handle, &receiver);
  for (int contacts : {10, 50000}) {
    auto bytes = session.Send(FullReply(contacts, contacts));
    ASSERT_TRUE(bytes);
    ASSERT_EQ(lcm.publish(channel, bytes->data(), static_cast<unsigned>(bytes->size())), 0);
    ASSERT_GT(lcm.handleTimeout(1000), 0);
  }
  ASSERT_EQ(receiver.messages.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto& message = receiver.messages[i];
    auto kind = IdentifyMessage(message.data(), message.size());
    ASSERT_TRUE(kind);
    EXPECT_EQ(*kind, MessageType::kSealed);
    auto reply = session.Receive(message);
    ASSERT_TRUE(reply) << reply.error().message;
    EXPECT_EQ(reply->num_contacts, i == 0 ? 10 : 50000);
  }
}

}  // namespace
}  // namespace far::protocol
