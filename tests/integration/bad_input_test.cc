// Hostile input against a real far-daemon. A message that cannot be authenticated (garbage,
// truncated, forged, replayed, for another session) is dropped unanswered and counted; an
// authenticated request or ring record that is bad gets a sealed error reply that names the
// problem; the session (where it can) goes on, and a second, well-behaved client is still
// served. Messages are built by hand with far::protocol (RawSession), so each test sends
// exactly the bytes it means to.
#include <fcntl.h>
#include <linux/falloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <future>
#include <limits>
#include <mutex>
#include <random>
#include <thread>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/ring_layout.h"
#include "far/protocol/version.h"

namespace far::integration {
namespace {

using protocol::ToWireStatus;

std::string Describe(const far_lcm::step_reply_t& reply) {
  return "status " + std::to_string(reply.status) + " (" + reply.status_name +
         "): " + reply.message;
}

bool ContainsAll(const std::string& text, std::initializer_list<std::string_view> parts,
                 std::string* missing) {
  for (std::string_view part : parts) {
    if (text.find(part) == std::string::npos) {
      *missing = std::string(part);
      return false;
    }
  }
  return true;
}

// The reply to step `step_id` is signed, has status `code` and a message containing `parts`.
::testing::AssertionResult StepFails(RawSession& raw, int64_t step_id, ErrorCode code,
                                     std::initializer_list<std::string_view> parts) {
  auto reply = raw.WaitStepReply(step_id);
  if (!reply) return ::testing::AssertionFailure() << "no signed step_reply_t for step " << step_id;
  if (reply->status != ToWireStatus(code)) {
    return ::testing::AssertionFailure()
           << "expected " << far::ToString(code) << ", got " << Describe(*reply);
  }
  std::string missing;
  if (!ContainsAll(reply->message, parts, &missing)) {
    return ::testing::AssertionFailure()
           << "message lacks \"" << missing << "\": " << reply->message;
  }
  return ::testing::AssertionSuccess() << reply->message;
}

// The reply to step `step_id` is signed and ok; returns its contacts through `contacts`.
::testing::AssertionResult StepSucceeds(RawSession& raw, int64_t step_id,
                                        std::vector<ContactPair>* contacts = nullptr) {
  auto reply = raw.WaitStepReply(step_id);
  if (!reply) return ::testing::AssertionFailure() << "no signed step_reply_t for step " << step_id;
  if (reply->status != 0) return ::testing::AssertionFailure() << Describe(*reply);
  auto result = protocol::ParseStepReply(*reply);
  if (!result) return ::testing::AssertionFailure() << far::ToString(result.error());
  if (contacts != nullptr) *contacts = result->contacts;
  return ::testing::AssertionSuccess();
}

// The daemon's count of messages it dropped unanswered.
int64_t RejectedTotal() {
  auto status = client::Client::Status(TestClientOptions("counter"));
  return status ? status->rejected_messages_total : -1;
}

// `count` messages sent since the count was `before` were dropped: the daemon counted them,
// and nothing at all came back on the session's reply channel (no answer helps a flood, and
// none may carry what the sender wrote).
::testing::AssertionResult Dropped(RawSession& raw, int64_t before, int count) {
  if (!WaitUntil([&] { return RejectedTotal() >= before + count; }, std::chrono::seconds(5))) {
    return ::testing::AssertionFailure()
           << "rejected_messages_total " << RejectedTotal() << ", want " << before + count;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  if (const auto replies = raw.RawReplies(); !replies.empty())
    return ::testing::AssertionFailure() << replies.size() << " messages came back";
  return ::testing::AssertionSuccess();
}

// Copies bytes into the ring's byte stream at `index` (wrapping), as a writer that ignores
// the protocol would.
void PokeRing(const protocol::RingRegion& ring, uint64_t index, const void* data, size_t size) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < size; ++i) ring.data[(index + i) & (ring.capacity - 1)] = bytes[i];
}

class BadInputTest : public DaemonTest {
 protected:
  void SetUp() override {
    // A small update ring so that scribbling and capacity cases are quick.
    ASSERT_NE(StartDaemon({"--ring-bytes", "1048576"}), nullptr);
    auto session = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "hostile");
    ASSERT_TRUE(session.ok()) << far::ToString(session.error());
    raw_ = std::move(*session);
  }
  void TearDown() override {
    raw_.reset();
    DaemonTest::TearDown();
  }
  // A valid object that the session can add after a failure.
  void ExpectSessionStillWorks(int64_t step_id, uint32_t object_id = 500) {
    ASSERT_TRUE(raw_->writer().AddObject(object_id, TriangleRow(2), Motion::kRigid, Pose{}).ok());
    ASSERT_TRUE(raw_->SendStep(step_id, SmallRequest()).ok());
    EXPECT_TRUE(StepSucceeds(*raw_, step_id));
  }
  std::unique_ptr<RawSession> raw_;
};

TEST_F(BadInputTest, TruncatedStepRequestsAreDroppedUnanswered) {
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 0, 0, SmallRequest());
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(bytes.ok());
  const int64_t before = RejectedTotal();
  // Cut inside request_id, and at the end of a string.
  auto cut = *bytes;
  cut.resize(56);
  ASSERT_TRUE(raw_->PublishRequest(cut).ok());
  cut = *bytes;
  cut.resize(cut.size() - 40);
  ASSERT_TRUE(raw_->PublishRequest(cut).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 2));
  ExpectSessionStillWorks(1);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, GarbageMessagesAreDroppedAndTheDaemonGoesOn) {
  std::mt19937_64 random(7);
  std::vector<uint8_t> garbage(300);
  for (auto& b : garbage) b = static_cast<uint8_t>(random());
  const int64_t before = RejectedTotal();
  ASSERT_TRUE(raw_->PublishRequest(garbage).ok());
  ASSERT_TRUE(raw_->PublishRequest(std::vector<uint8_t>{1, 2, 3}).ok());
  ASSERT_TRUE(raw_->PublishRequest(std::vector<uint8_t>{}).ok());
  // A step request whose method string claims 2^31 - 1 bytes (LCM's decode would allocate).
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 0, 0, SmallRequest());
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(bytes.ok());
  const size_t method_length_at = 8 + 4 + 8 + 32 + 8 + 8 + 8;  // after ring_commit_sequence
  (*bytes)[method_length_at] = 0x7f;
  (*bytes)[method_length_at + 1] = 0xff;
  (*bytes)[method_length_at + 2] = 0xff;
  (*bytes)[method_length_at + 3] = 0xff;
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  // A daemon-to-client type sent to the daemon.
  far_lcm::step_reply_t reply{};
  reply.protocol_version = protocol::kProtocolVersion;
  reply.session_id = raw_->id();
  reply.request_id = raw_->NextRequestId();
  reply.status_name = "ok";
  reply.message = "";
  reply.output = "contacts";
  auto reply_bytes = protocol::EncodeSigned(reply, raw_->key());
  ASSERT_TRUE(reply_bytes.ok());
  ASSERT_TRUE(raw_->PublishRequest(*reply_bytes).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 5));
  ExpectSessionStillWorks(1);
  EXPECT_TRUE(HealthyClientSteps());
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status.ok());
  bool parse_errors = false;
  for (const auto& [kind, count] : status->errors_by_kind) parse_errors |= kind == "parse_error";
  EXPECT_TRUE(parse_errors) << "dropped messages are counted by kind";
}

TEST_F(BadInputTest, WrongProtocolVersionIsDroppedOrRefusedInTheAskersTerms) {
  // A session message of another protocol version: dropped (it cannot be authenticated).
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 0, 0, SmallRequest());
  message.protocol_version = protocol::kProtocolVersion + 1;
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(bytes.ok());
  const int64_t before = RejectedTotal();
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 1));

  // An open request of another version gets a version_mismatch answer on the socket.
  far_lcm::open_session_t open = MakeOpenSession("from-the-future");
  open.protocol_version = protocol::kProtocolVersion + 1;
  auto answer = AskDaemon(CurrentSocketPath(), *protocol::EncodeMessage(open));
  ASSERT_TRUE(answer.ok()) << far::ToString(answer.error());
  auto reply = protocol::DecodeMessageAnyVersion<far_lcm::open_session_reply_t>(
      answer->data(), answer->size(), protocol::kMaxControlMessageBytes);
  ASSERT_TRUE(reply.ok()) << far::ToString(reply.error());
  EXPECT_EQ(reply->request_id, open.request_id);
  EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kVersionMismatch));
  EXPECT_EQ(reply->status_name, "version_mismatch");
  EXPECT_NE(reply->message.find("protocol_version: got " + std::to_string(protocol::kProtocolVersion + 1) + ", expected " + std::to_string(protocol::kProtocolVersion)), std::string::npos)
      << reply->message;
  EXPECT_EQ(reply->session_id, 0);

  ExpectSessionStillWorks(1);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, MessagesForUnknownOrOtherSessionsAreDropped) {
  // A session that does not exist (signed with some key: it cannot be checked anyway).
  constexpr int64_t kUnknown = 987654;
  protocol::SessionKey some_key{};
  some_key.fill(3);
  auto message = protocol::MakeStepRequest(kUnknown, 1, 0, 0, SmallRequest());
  auto bytes = protocol::EncodeSigned(message, some_key);
  ASSERT_TRUE(bytes.ok());
  const int64_t before = RejectedTotal();
  ASSERT_TRUE(
      raw_->listener().Publish(protocol::SessionRequestChannel("FAR_", kUnknown), *bytes).ok());
  // Our session's channel, another session id in the message.
  auto other =
      protocol::MakeStepRequest(raw_->id() + 5, raw_->NextRequestId(), 0, 0, SmallRequest());
  ASSERT_TRUE(raw_->PublishRequest(*protocol::EncodeSigned(other, raw_->key())).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 2));
  // A channel name that only looks like a session's is not even delivered to the daemon.
  ASSERT_TRUE(raw_->listener().Publish("FAR_S0001_REQ", *bytes).ok());
  ExpectSessionStillWorks(1);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, ForgedTagsAreDroppedAndDoNotAdvanceTheReplayWindow) {
  // A tag made with the wrong key, with a request id far ahead.
  protocol::SessionKey wrong = raw_->key();
  wrong[0] ^= 1;
  auto forged = protocol::MakeStepRequest(raw_->id(), 1000, 0, 0, SmallRequest());
  auto bytes = protocol::EncodeSigned(forged, wrong);
  ASSERT_TRUE(bytes.ok());
  const int64_t before = RejectedTotal();
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  // No tag at all (zero auth), and a valid tag over changed bytes.
  ASSERT_TRUE(raw_->PublishRequest(*protocol::EncodeMessage(forged)).ok());
  auto tampered = protocol::EncodeSigned(forged, raw_->key());
  tampered->back() ^= 0x40;  // a byte of timeout_ms
  ASSERT_TRUE(raw_->PublishRequest(*tampered).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 3));
  // The real client's next request id (small) still works: forgeries did not move the window.
  ExpectSessionStillWorks(0);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, ReplayedRequestIsDroppedUnanswered) {
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 0,
                                           raw_->writer().last_sequence(), SmallRequest());
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(bytes.ok());
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  ASSERT_TRUE(StepSucceeds(*raw_, 0));
  raw_->listener().Clear();
  // The same bytes again (a sniffed message replayed).
  const int64_t before = RejectedTotal();
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  EXPECT_TRUE(Dropped(*raw_, before, 1));
  ExpectSessionStillWorks(1);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, RecordRunningPastTheWrittenEndCorruptsOnlyThatSession) {
  const protocol::RingRegion ring = raw_->segment().update_ring();
  // Record 1 claims 4096 bytes; only 64 are published.
  const protocol::RecordHeader header{static_cast<uint32_t>(protocol::RecordType::kAddObject), 4096,
                                      1};
  PokeRing(ring, 0, &header, sizeof(header));
  ring.write_index->store(64, std::memory_order_release);
  ASSERT_TRUE(raw_->SendStep(0, SmallRequest(), 1).ok());
  EXPECT_TRUE(StepFails(
      *raw_, 0, ErrorCode::kParseError,
      {"update ring: record 1", "runs past the end of the committed data", "ring is corrupt"}));
  // Framing is lost: later steps of this session fail the same way, even with nothing new.
  ASSERT_TRUE(raw_->SendStep(1, SmallRequest(), 1).ok());
  EXPECT_TRUE(StepFails(*raw_, 1, ErrorCode::kParseError, {"ring is corrupt; open a new session"}));
  ASSERT_TRUE(raw_->SendStep(2, SmallRequest(), 2).ok());
  EXPECT_TRUE(StepFails(*raw_, 2, ErrorCode::kParseError, {"ring is corrupt"}));
  // Other sessions are fine.
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, WriteIndexOrRecordSizePastTheCapacityIsAFramingError) {
  // A write index more than one capacity ahead of the daemon's read index.
  const protocol::RingRegion ring = raw_->segment().update_ring();
  ring.write_index->store(ring.capacity + 64, std::memory_order_release);
  ASSERT_TRUE(raw_->SendStep(0, SmallRequest(), 1).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kParseError,
                        {"write_index", "more than the capacity", "ring is corrupt"}));

  // A second session: a whole ring "committed", and a record claiming nearly 4 GiB.
  auto second = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "hostile-2");
  ASSERT_TRUE(second.ok()) << far::ToString(second.error());
  const protocol::RingRegion ring2 = (*second)->segment().update_ring();
  const protocol::RecordHeader huge{static_cast<uint32_t>(protocol::RecordType::kSetVertices),
                                    0xFFFFFFF8u, 1};
  PokeRing(ring2, 0, &huge, sizeof(huge));
  ring2.write_index->store(ring2.capacity, std::memory_order_release);
  ASSERT_TRUE((*second)->SendStep(0, SmallRequest(), 1).ok());
  EXPECT_TRUE(
      StepFails(**second, 0, ErrorCode::kParseError, {"size 4294967288", "runs past the end"}));

  // A third: a record size that is not a multiple of 8, and one smaller than its header.
  auto third = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "hostile-3");
  ASSERT_TRUE(third.ok()) << far::ToString(third.error());
  const protocol::RingRegion ring3 = (*third)->segment().update_ring();
  const protocol::RecordHeader odd{static_cast<uint32_t>(protocol::RecordType::kRemoveObject), 20,
                                   1};
  PokeRing(ring3, 0, &odd, sizeof(odd));
  ring3.write_index->store(24, std::memory_order_release);
  ASSERT_TRUE((*third)->SendStep(0, SmallRequest(), 1).ok());
  EXPECT_TRUE(StepFails(**third, 0, ErrorCode::kParseError, {"not a multiple of 8"}));

  // A commit sequence beyond what was written is a plain error: nothing is consumed and the
  // same request works once the records are there.
  auto fourth = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "hostile-4");
  ASSERT_TRUE(fourth.ok()) << far::ToString(fourth.error());
  ASSERT_TRUE((*fourth)->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE((*fourth)->SendStep(0, SmallRequest(), 2).ok());
  EXPECT_TRUE(StepFails(**fourth, 0, ErrorCode::kInvalidArgument, {"sequence 2 is not committed"}));
  ASSERT_TRUE((*fourth)->writer().AddObject(2, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE((*fourth)->SendStep(1, SmallRequest(), 2).ok());
  EXPECT_TRUE(StepSucceeds(**fourth, 1));

  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, TriangleIndexOutOfRangeIsRejectedAndTheStepIsDiscarded) {
  // Record 1 is fine, record 2 has a triangle index past its vertices.
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  Mesh bad = TriangleRow(2);
  bad.triangles[1][2] = 7;
  ASSERT_TRUE(raw_->writer().AddObject(2, bad, Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(0, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kInvalidArgument,
                        {"record 2 (add_object)", "triangles[1][2]: 7 is not < vertex_count 6",
                         "records 1..2 of this step were discarded"}));
  // All or nothing: object 1 was not added either, so adding it again works.
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(1, SmallRequest()).ok());
  EXPECT_TRUE(StepSucceeds(*raw_, 1));
  // Scene-level checks: an unknown id, a pose for a static object.
  ASSERT_TRUE(raw_->writer().RemoveObject(77).ok());
  ASSERT_TRUE(raw_->SendStep(2, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 2, ErrorCode::kNotFound, {"object 77", "is not in the scene"}));
  ASSERT_TRUE(raw_->writer().AddObject(3, TriangleRow(1), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE(raw_->writer().SetPose(3, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(3, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 3, ErrorCode::kInvalidArgument, {"object 3", "static"}));
  ExpectSessionStillWorks(4);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, NonFiniteVerticesAndPosesAreRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Mesh with_nan = TriangleRow(2);
  with_nan.p_MV[4].y() = nan;
  ASSERT_TRUE(raw_->writer().AddObject(1, with_nan, Motion::kDeformable, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(0, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kInvalidArgument, {"p_MV[4].y: nan is not finite"}));

  Mesh with_inf = TriangleRow(2);
  with_inf.p_MV[0].z() = -inf;
  ASSERT_TRUE(raw_->writer().AddObject(1, with_inf, Motion::kDeformable, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(1, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 1, ErrorCode::kInvalidArgument, {"p_MV[0].z: -inf is not finite"}));

  Mesh far_away = TriangleRow(1);
  far_away.p_MV[1].x() = 1e300;
  ASSERT_TRUE(raw_->writer().AddObject(1, far_away, Motion::kDeformable, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(2, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 2, ErrorCode::kInvalidArgument, {"p_MV[1].x", "beyond"}));

  // A good deformable object, then bad vertex and pose updates for it.
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(2), Motion::kDeformable, Pose{}).ok());
  ASSERT_TRUE(raw_->SendStep(3, SmallRequest()).ok());
  ASSERT_TRUE(StepSucceeds(*raw_, 3));
  std::vector<Eigen::Vector3d> moved = TriangleRow(2).p_MV;
  moved[5].x() = inf;
  ASSERT_TRUE(raw_->writer().SetVertices(1, moved).ok());
  ASSERT_TRUE(raw_->SendStep(4, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 4, ErrorCode::kInvalidArgument,
                        {"set_vertices", "p_MV[5].x: inf is not finite"}));
  Pose nan_pose;
  nan_pose.translation.y() = nan;
  ASSERT_TRUE(raw_->writer().SetPose(1, nan_pose).ok());
  ASSERT_TRUE(raw_->SendStep(5, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 5, ErrorCode::kInvalidArgument,
                        {"set_pose", "X_WO.t.y: nan is not finite"}));
  Pose unnormalized;
  unnormalized.rotation = Eigen::Quaterniond(2, 0, 0, 0);
  ASSERT_TRUE(raw_->writer().SetPose(1, unnormalized).ok());
  ASSERT_TRUE(raw_->SendStep(6, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 6, ErrorCode::kInvalidArgument, {"X_WO: rotation_wxyz", "norm 2"}));
  // Wrong vertex count for the object.
  ASSERT_TRUE(raw_->writer().SetVertices(1, TriangleRow(1).p_MV).ok());
  ASSERT_TRUE(raw_->SendStep(7, SmallRequest()).ok());
  EXPECT_TRUE(
      StepFails(*raw_, 7, ErrorCode::kInvalidArgument, {"3 vertices given, object 1 has 6"}));

  ExpectSessionStillWorks(8);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, BadStepRequestFieldsAreNamed) {
  StepRequest low = SmallRequest();
  low.resolution = 5;
  ASSERT_TRUE(raw_->SendStep(0, low).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kInvalidArgument, {"resolution", "5"}));
  StepRequest nan_distance = SmallRequest();
  nan_distance.distance = std::numeric_limits<double>::quiet_NaN();
  nan_distance.output = Output::kDistancePairs;
  ASSERT_TRUE(raw_->SendStep(1, nan_distance).ok());
  EXPECT_TRUE(StepFails(*raw_, 1, ErrorCode::kInvalidArgument, {"distance"}));
  // An unknown method name, sent by hand.
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 2, 0, SmallRequest());
  message.method = "teleport";
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  EXPECT_TRUE(StepFails(*raw_, 2, ErrorCode::kInvalidArgument, {"method", "teleport"}));
  ExpectSessionStillWorks(3);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, RingScribbledWhileTheDaemonReadsGetsErrorsNotACrash) {
  DaemonProcess& daemon = *daemons_.front();
  int answered = 0, failed = 0, succeeded = 0;
  // Several sessions in turn. Even ones: a thread overwrites only the payloads of published
  // records (positions, triangle indices) while the daemon drains them: content errors, the
  // framing holds and the session goes on. Odd ones: it overwrites anything, headers and
  // indices included (once a ring is corrupt every step fails the same way).
  for (int s = 0; s < 4; ++s) {
    SCOPED_TRACE("session " + std::to_string(s));
    const bool payload_only = s % 2 == 0;
    auto session =
        RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "scribbled-" + std::to_string(s));
    ASSERT_TRUE(session.ok()) << far::ToString(session.error());
    RawSession& raw = **session;
    const protocol::RingRegion ring = raw.segment().update_ring();
    const protocol::RingRegion reply_ring = raw.segment().reply_ring();
    std::mutex mutex;
    std::vector<std::pair<uint64_t, uint64_t>> payloads;  // [begin, end) ring indices
    // The writer's index as the scribbler may read it: the writer itself is this thread's (the
    // shared-memory races are the point of the test, a race on the writer's own state is not).
    std::atomic<uint64_t> written{0};
    auto add = [&](uint32_t id) {
      auto at = raw.writer().AddObject(id, TriangleRow(40), Motion::kRigid, Pose{});
      // With the daemon-owned read index scribbled, our own writer may refuse (kParseError).
      if (!payload_only && !at.ok()) return;
      ASSERT_TRUE(at.ok()) << far::ToString(at.error());
      written = raw.writer().ring().write_index();
      std::lock_guard lock(mutex);
      payloads.emplace_back(at->index + sizeof(protocol::AddObjectRecord), at->index + at->size);
    };
    for (uint32_t id = 1; id <= 4; ++id) add(id);
    std::atomic<bool> stop{false};
    std::thread scribbler([&, seed = 100 + s] {
      std::mt19937_64 random(seed);
      while (!stop) {
        uint8_t junk[64];
        for (auto& b : junk) b = static_cast<uint8_t>(random());
        if (payload_only) {
          std::pair<uint64_t, uint64_t> range;
          {
            std::lock_guard lock(mutex);
            range = payloads[random() % payloads.size()];
          }
          const uint64_t at = range.first + random() % (range.second - range.first);
          PokeRing(ring, at, junk,
                   std::min<uint64_t>(1 + random() % sizeof(junk), range.second - at));
          continue;
        }
        const uint64_t written_index = written.load();
        switch (random() % 8) {
          case 0:
          case 1:
          case 2:
          case 3:
            // Random bytes anywhere in the records, headers included.
            PokeRing(ring, random() % written_index, junk, 1 + random() % sizeof(junk));
            break;
          case 4: {
            // Plausible-looking headers with wrong sizes and sequences.
            const protocol::RecordHeader h{static_cast<uint32_t>(1 + random() % 4),
                                           static_cast<uint32_t>((random() % 512) * 8),
                                           random() % 6};
            PokeRing(ring, (random() % (written_index / 8)) * 8, &h, sizeof(h));
            break;
          }
          case 5:
            ring.write_index->store(random() % (2 * ring.capacity), std::memory_order_release);
            break;
          case 6:
            ring.write_index->store(written_index, std::memory_order_release);
            break;
          default:
            // The daemon-owned index and the reply ring's are fair game for a hostile client.
            ring.read_index->store(random(), std::memory_order_release);
            reply_ring.read_index->store(random() % 3 == 0 ? random() : 0,
                                         std::memory_order_release);
        }
      }
    });
    for (int step = 0; step < 6; ++step) {
      add(static_cast<uint32_t>(10 + step));
      ASSERT_TRUE(raw.SendStep(step, SmallRequest()).ok());
      auto reply = raw.WaitStepReply(step);
      EXPECT_TRUE(reply.has_value()) << "no reply to step " << step;
      if (!reply) continue;
      ++answered;
      if (reply->status == 0) {
        ++succeeded;
        continue;
      }
      ++failed;
      EXPECT_FALSE(reply->message.empty());
      if (payload_only) {
        EXPECT_EQ(reply->message.find("corrupt"), std::string::npos) << reply->message;
        EXPECT_NE(reply->message.find("of this step were discarded"), std::string::npos)
            << reply->message;
      }
    }
    stop = true;
    scribbler.join();
    ASSERT_TRUE(daemon.Running()) << "far-daemon died";
  }
  EXPECT_EQ(answered, 24);
  EXPECT_GT(failed, 0);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, TheClientCannotResizeTheSegmentAndHolesAreZerosNotASigbus) {
  DaemonProcess& daemon = *daemons_.front();
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(2), Motion::kRigid, Pose{}).ok());
  // Shrinking would make the daemon's next ring access raise SIGBUS: the seals forbid it.
  ASSERT_GE(raw_->segment_fd(), 0);
  EXPECT_NE(ftruncate(raw_->segment_fd(), 4096), 0);
  EXPECT_EQ(errno, EPERM);
  // Punching a hole is allowed, and reads back zeros: the records the daemon reads are then
  // nonsense, which is an error for this session only.
  const auto& layout = raw_->segment().layout();
  ASSERT_EQ(fallocate(raw_->segment_fd(), FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE,
                      static_cast<off_t>(layout.update_ring_offset),
                      static_cast<off_t>(layout.update_ring_capacity)),
            0);
  ASSERT_TRUE(raw_->SendStep(0, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kParseError, {"update ring"}));
  EXPECT_TRUE(daemon.Running());
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, OpenRequestsAreCheckedAndAnsweredOnTheirOwnConnection) {
  auto ask =
      [&](const far_lcm::open_session_t& open) -> std::optional<far_lcm::open_session_reply_t> {
    auto answer = AskDaemon(CurrentSocketPath(), *protocol::EncodeMessage(open));
    if (!answer) return std::nullopt;
    auto reply = protocol::DecodeMessage<far_lcm::open_session_reply_t>(
        answer->data(), answer->size(), protocol::kMaxControlMessageBytes);
    if (!reply) return std::nullopt;
    return *reply;
  };
  auto reply = ask(MakeOpenSession("evil\nlevel=error event=forged"));
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kInvalidArgument));
  EXPECT_NE(reply->message.find("client_name"), std::string::npos) << reply->message;
  EXPECT_EQ(reply->message.find('\n'), std::string::npos)
      << "client text must be escaped: " << reply->message;

  far_lcm::open_session_t bad_ring = MakeOpenSession("odd-ring");
  bad_ring.update_ring_bytes = 100000;
  reply = ask(bad_ring);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kInvalidArgument));
  EXPECT_NE(reply->message.find("update_ring_bytes"), std::string::npos) << reply->message;

  // A first message that is neither an open nor a status request: no answer at all.
  const int64_t before = RejectedTotal();
  auto garbage = AskDaemon(CurrentSocketPath(), std::vector<uint8_t>(64, 0x41),
                           std::chrono::milliseconds(1000));
  ASSERT_FALSE(garbage.ok());
  EXPECT_EQ(garbage.error().code, ErrorCode::kUnavailable) << garbage.error().message;
  EXPECT_TRUE(WaitUntil([&] { return RejectedTotal() > before; }, std::chrono::seconds(3)));
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->sessions_open, 1) << "only the hostile session is open";
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(BadInputTest, NegativeCommitSequenceIsRejected) {
  auto message = protocol::MakeStepRequest(raw_->id(), raw_->NextRequestId(), 0, 0, SmallRequest());
  message.ring_commit_sequence = -5;
  auto bytes = protocol::EncodeSigned(message, raw_->key());
  ASSERT_TRUE(raw_->PublishRequest(*bytes).ok());
  EXPECT_TRUE(StepFails(*raw_, 0, ErrorCode::kInvalidArgument, {"ring_commit_sequence"}));
  ExpectSessionStillWorks(1);
}

TEST_F(BadInputTest, StepFloodIsAnsweredWithBusyWhileOthersAreServed) {
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(20), Motion::kRigid, Pose{}).ok());
  StepRequest request = SmallRequest();
  request.resolution = 512;
  constexpr int kSteps = 40;
  for (int step = 0; step < kSteps; ++step) ASSERT_TRUE(raw_->SendStep(step, request).ok());
  // A well-behaved client gets its turn during the flood.
  auto healthy = std::async(std::launch::async, [] { return HealthyClientSteps("during-flood"); });
  int ok = 0, busy = 0;
  for (int step = 0; step < kSteps; ++step) {
    auto reply = raw_->WaitStepReply(step);
    ASSERT_TRUE(reply.has_value()) << "no reply to step " << step;
    if (reply->status == 0) {
      ++ok;
    } else {
      EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kBusy)) << Describe(*reply);
      EXPECT_NE(reply->message.find("pending"), std::string::npos) << reply->message;
      ++busy;
    }
  }
  EXPECT_GT(ok, 0);
  EXPECT_GT(busy, 0) << "40 requests at once should overflow the per-session queue of 4";
  EXPECT_TRUE(healthy.get());
}

TEST_F(BadInputTest, ResolutionOverTheDaemonsLimitIsRefused) {
  // A huge viewport costs every session its share of the GPU: the daemon caps it.
  ASSERT_TRUE(raw_->writer().AddObject(1, TriangleRow(2), Motion::kRigid, Pose{}).ok());
  StepRequest request = SmallRequest();
  request.resolution = 8192;  // valid on the wire, over the default max_resolution 4096
  ASSERT_TRUE(raw_->SendStep(0, request).ok());
  auto reply = raw_->WaitStepReply(0);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kLimitExceeded)) << Describe(*reply);
  EXPECT_NE(reply->message.find("max_resolution"), std::string::npos) << reply->message;
  EXPECT_TRUE(HealthyClientSteps("after-huge-resolution"));
}

TEST_F(BadInputTest, BurstFromOneSessionDoesNotDropAnotherSessionsRequests) {
  // A well-behaved client steps right after another session sent a burst of 200 garbage
  // messages. LCM queues received messages per subscription (30 by default, then it drops),
  // and the request channels of all sessions share one subscription: the burst must not make
  // the daemon lose the neighbour's request.
  auto healthy = client::Client::Connect(TestClientOptions("burst-neighbour"));
  ASSERT_TRUE(healthy.ok()) << far::ToString(healthy.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*healthy)->LoadScene(scene).ok());
  const auto expected = ReferenceContacts(scene.objects);
  const std::vector<uint8_t> garbage(1000, 0x5A);
  for (int round = 0; round < 5; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    for (int i = 0; i < 200; ++i) ASSERT_TRUE(raw_->PublishRequest(garbage).ok());
    auto result = (*healthy)->Step(SmallRequest());
    ASSERT_TRUE(result.ok()) << far::ToString(result.error());
    EXPECT_EQ(result->contacts, expected);
  }
  EXPECT_TRUE(daemons_.front()->Running());
}

TEST_F(BadInputTest, ReplyRingReadIndexScribbledIsAnErrorAndTheSessionRecovers) {
  // Two coinciding grids: thousands of contacts, a reply far above the 63 KiB inline limit.
  ASSERT_TRUE(raw_->writer().AddObject(1, FlatGrid(40), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw_->writer().AddObject(2, FlatGrid(40), Motion::kRigid, Pose{}).ok());
  StepRequest request = SmallRequest(Method::kAabb);
  ASSERT_TRUE(raw_->SendStep(0, request).ok());
  auto big = raw_->WaitReply([](const ReplyMessage& m) { return m.step && m.step->step_id == 0; });
  ASSERT_TRUE(big.has_value());
  ASSERT_EQ(big->step->status, 0) << big->step->message;
  EXPECT_TRUE(big->from_shm) << big->step->num_contacts << " contacts came inline";
  const int32_t contacts = big->step->num_contacts;
  EXPECT_GT(contacts, 4096);

  // The client-owned read index of the reply ring, scribbled: the daemon cannot write the
  // reply and says so (inline), instead of trusting the index.
  const protocol::RingRegion reply_ring = raw_->segment().reply_ring();
  reply_ring.read_index->store(uint64_t{1} << 40, std::memory_order_release);
  ASSERT_TRUE(raw_->SendStep(1, request).ok());
  EXPECT_TRUE(StepFails(*raw_, 1, ErrorCode::kParseError, {"reply ring", "read index"}));
  // Restored, the same step works again through the ring.
  reply_ring.read_index->store(raw_->reply_reader().read_index(), std::memory_order_release);
  ASSERT_TRUE(raw_->SendStep(2, request).ok());
  auto again =
      raw_->WaitReply([](const ReplyMessage& m) { return m.step && m.step->step_id == 2; });
  ASSERT_TRUE(again.has_value());
  ASSERT_EQ(again->step->status, 0) << again->step->message;
  EXPECT_TRUE(again->from_shm);
  EXPECT_EQ(again->step->num_contacts, contacts);
  EXPECT_TRUE(HealthyClientSteps());
}

class LimitsTest : public DaemonTest {};

TEST_F(LimitsTest, CountsOverTheLimitsAreLimitExceeded) {
  // Room for the healthy client's scene (8 objects, 192 triangles), little more.
  ASSERT_NE(StartDaemon({"--max-triangles", "200", "--max-vertices", "600", "--max-objects", "8",
                         "--max-sessions", "3"}),
            nullptr);
  auto session = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "greedy");
  ASSERT_TRUE(session.ok()) << far::ToString(session.error());
  RawSession& raw = **session;

  // One record over the per-record triangle limit (200).
  ASSERT_TRUE(raw.writer().AddObject(1, TriangleFan(250), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.SendStep(0, SmallRequest()).ok());
  EXPECT_TRUE(
      StepFails(raw, 0, ErrorCode::kLimitExceeded, {"triangle_count: 250 is over the limit 200"}));
  // One over the per-record vertex limit (3 x 200).
  ASSERT_TRUE(raw.writer().AddObject(1, TriangleRow(201), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.SendStep(1, SmallRequest()).ok());
  EXPECT_TRUE(
      StepFails(raw, 1, ErrorCode::kLimitExceeded, {"vertex_count: 603 is over the limit 600"}));
  // A record claiming 2^32 - 1 vertices (written by hand: no client library would).
  protocol::AddObjectRecord fixed{};
  fixed.object_id = 2;
  fixed.motion = 1;
  fixed.vertex_count = 0xFFFFFFFFu;
  fixed.triangle_count = 1;
  fixed.X_WO[3] = 1;
  std::vector<uint8_t> padding(64, 0);
  ASSERT_TRUE(raw.writer()
                  .ring()
                  .Write(protocol::RecordType::kAddObject,
                         {std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(&fixed) + 16,
                                                   sizeof(fixed) - 16),
                          padding})
                  .ok());
  ASSERT_TRUE(raw.SendStep(2, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(raw, 2, ErrorCode::kLimitExceeded,
                        {"vertex_count: 4294967295 is over the limit 600"}));
  // The session total: 150 + 150 > 200.
  ASSERT_TRUE(raw.writer().AddObject(1, TriangleFan(150), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.writer().AddObject(2, TriangleFan(150), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.SendStep(3, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(raw, 3, ErrorCode::kLimitExceeded,
                        {"the scene would have 300 triangles (limit 200)"}));
  // Objects: 9 > 8.
  for (uint32_t id = 1; id <= 9; ++id) {
    ASSERT_TRUE(raw.writer().AddObject(id, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  }
  ASSERT_TRUE(raw.SendStep(4, SmallRequest()).ok());
  EXPECT_TRUE(StepFails(raw, 4, ErrorCode::kLimitExceeded, {"more than 8 objects"}));
  // Within the limits, the session goes on.
  for (uint32_t id = 1; id <= 8; ++id) {
    ASSERT_TRUE(raw.writer().AddObject(id, TriangleRow(25), Motion::kRigid, Pose{}).ok());
  }
  ASSERT_TRUE(raw.SendStep(5, SmallRequest()).ok());
  EXPECT_TRUE(StepSucceeds(raw, 5));

  // Sessions: 3 allowed; the fourth open is refused with a reason.
  auto second = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "greedy-2");
  ASSERT_TRUE(second.ok());
  auto third = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "greedy-3");
  ASSERT_TRUE(third.ok());
  auto fourth = client::Client::Connect(TestClientOptions("one-too-many"));
  ASSERT_FALSE(fourth.ok());
  EXPECT_EQ(fourth.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(fourth.error().message.find("max_sessions"), std::string::npos)
      << fourth.error().message;
  // Closing one (its client lets go of the connection) makes room for the healthy client.
  const std::string third_segment = (*third)->segment().name();
  const pid_t daemon_pid = daemons_.front()->pid();
  (*third)->Disconnect();
  EXPECT_TRUE(WaitUntil(
      [&] {
        const auto mapped = SessionSegmentsOf(daemon_pid);
        return std::find(mapped.begin(), mapped.end(), third_segment) == mapped.end();
      },
      std::chrono::seconds(3)))
      << third_segment << " is still mapped by the daemon after its client left";
  EXPECT_TRUE(HealthyClientSteps());
}

}  // namespace
}  // namespace far::integration
