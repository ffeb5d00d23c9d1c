// Sessions that end badly: clients that stop sending heartbeats, clients killed in the middle
// of writing an update, a daemon killed with SIGKILL and started again, no daemon at all.
#include <signal.h>

#include <algorithm>
#include <future>
#include <sstream>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/shm_reply.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using protocol::ToWireStatus;

constexpr int kHeartbeatTimeoutMs = 600;
const std::vector<std::string> kShortHeartbeat = {"--heartbeat-timeout-ms",
                                                  std::to_string(kHeartbeatTimeoutMs)};

bool SessionListed(int64_t id) {
  auto status = client::Client::Status(TestLcmUrl(), 3s);
  if (!status) return true;  // unknown: treat as "still there" so the check fails loudly
  return std::any_of(status->sessions.begin(), status->sessions.end(),
                     [&](const auto& s) { return s.id == id; });
}

using SessionLifetimeTest = DaemonTest;

TEST_F(SessionLifetimeTest, SessionWithoutHeartbeatsIsClosedAndItsSegmentRemoved) {
  ASSERT_NE(StartDaemon(kShortHeartbeat), nullptr);
  // The daemon's clock for the session starts after this (when the open request arrives).
  const auto opened = std::chrono::steady_clock::now();
  auto silent = RawSession::Open(TestLcmUrl(), "silent");
  auto chatty = RawSession::Open(TestLcmUrl(), "chatty");
  ASSERT_TRUE(silent.ok()) << far::ToString(silent.error());
  ASSERT_TRUE(chatty.ok()) << far::ToString(chatty.error());
  const std::string silent_shm = (*silent)->shm_name();
  ASSERT_TRUE(ShmExists(silent_shm));
  EXPECT_TRUE(SessionListed((*silent)->id()));

  // The chatty one sends a heartbeat every 150 ms while the silent one says nothing.
  const auto start = std::chrono::steady_clock::now();
  std::optional<ReplyMessage> closed;
  while (std::chrono::steady_clock::now() - start < 4s && !closed) {
    ASSERT_TRUE((*chatty)->SendHeartbeat().ok());
    closed = (*silent)->WaitReply(
        [](const ReplyMessage& m) { return m.error && m.error->session_closed; }, 150ms);
  }
  const auto waited = std::chrono::steady_clock::now() - opened;
  ASSERT_TRUE(closed.has_value()) << "no session_closed error_t within 4 s";
  EXPECT_GE(waited, std::chrono::milliseconds(kHeartbeatTimeoutMs - 50));
  EXPECT_TRUE(closed->signed_ok) << "the closing error_t must carry the session's tag";
  EXPECT_EQ(closed->error->status, ToWireStatus(ErrorCode::kTimeout));
  EXPECT_NE(closed->error->message.find("no heartbeat for 600 ms"), std::string::npos)
      << closed->error->message;
  EXPECT_TRUE(WaitUntil([&] { return !ShmExists(silent_shm); }, 3s))
      << silent_shm << " is still in /dev/shm";
  EXPECT_FALSE(SessionListed((*silent)->id()));

  // The chatty session is alive: its heartbeats are echoed, signed, and a step works.
  auto echo =
      (*chatty)->WaitReply([](const ReplyMessage& m) { return m.heartbeat.has_value(); }, 2s);
  ASSERT_TRUE(echo.has_value());
  EXPECT_TRUE(echo->signed_ok);
  EXPECT_TRUE(SessionListed((*chatty)->id()));
  ASSERT_TRUE((*chatty)->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE((*chatty)->SendStep(0, SmallRequest()).ok());
  auto reply = (*chatty)->WaitStepReply(0);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, 0) << reply->message;

  // The closed session's messages are now for an unknown session.
  auto late = (*silent)->SendStep(0, SmallRequest());
  ASSERT_TRUE(late.ok());
  auto refused = (*silent)->WaitError(*late);
  ASSERT_TRUE(refused.has_value());
  EXPECT_EQ(refused->error->status, ToWireStatus(ErrorCode::kNotFound));
  EXPECT_NE(refused->error->message.find("no open session"), std::string::npos)
      << refused->error->message;

  EXPECT_TRUE(HealthyClientSteps());
}

// A child (this binary in --far-half-writer mode) opens a session and dies while writing.
struct DeadWriter {
  int64_t session_id = 0;
  std::string shm_name;
  protocol::SessionKey key{};
};

std::optional<DeadWriter> ReadWriterLine(ChildProcess& child) {
  auto line = child.ReadLine(10s);
  if (!line) return std::nullopt;
  DeadWriter writer;
  std::istringstream in(*line);
  std::string key_hex;
  in >> writer.session_id >> writer.shm_name >> key_hex;
  if (!in || key_hex.size() != 64) return std::nullopt;
  for (size_t i = 0; i < writer.key.size(); ++i) {
    writer.key[i] = static_cast<uint8_t>(std::stoi(key_hex.substr(2 * i, 2), nullptr, 16));
  }
  return writer;
}

class KilledClientTest : public DaemonTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(KilledClientTest, SessionOfADeadWriterIsClosedAfterTheHeartbeatTimeout) {
  DaemonProcess* daemon = StartDaemon(kShortHeartbeat);
  ASSERT_NE(daemon, nullptr);
  const std::string mode = GetParam();
  // Listen to every session's replies before the child speaks.
  auto listener = Listener::Create(TestLcmUrl());
  ASSERT_TRUE(listener.ok());
  (*listener)->Subscribe("FAR_S[0-9]+_REPLY");
  (*listener)->Start();

  auto child = ChildProcess::Spawn({SelfPath(), "--far-half-writer", mode});
  ASSERT_TRUE(child.ok()) << far::ToString(child.error());
  auto writer = ReadWriterLine(**child);
  ASSERT_TRUE(writer.has_value()) << "the half-writer did not report its session";
  EXPECT_TRUE(ShmExists(writer->shm_name));
  if (mode == "killed") {
    std::this_thread::sleep_for(300ms);
    EXPECT_EQ((*child)->Kill(), 128 + SIGKILL);
  } else {
    EXPECT_EQ((*child)->Wait(10s), std::optional<int>(0));
  }

  if (mode == "index-mid-record") {
    // The dead client's step got its answer: the half-written record is a framing error.
    const std::string channel = protocol::SessionReplyChannel(writer->session_id);
    auto got = (*listener)->WaitFor(
        [&](const Received& r) {
          return r.channel == channel &&
                 protocol::IdentifyMessage(r.bytes.data(), r.bytes.size()).ok() &&
                 *protocol::IdentifyMessage(r.bytes.data(), r.bytes.size()) ==
                     protocol::MessageType::kStepReply;
        },
        5s);
    ASSERT_TRUE(got.has_value()) << "no step reply for the dead client's step";
    ASSERT_TRUE(protocol::VerifyEncoded(got->bytes, writer->key).ok());
    auto reply = protocol::DecodeMessage<far_lcm::step_reply_t>(
        got->bytes.data(), got->bytes.size(), protocol::kMaxStepReplyBytes);
    ASSERT_TRUE(reply.ok());
    EXPECT_EQ(reply->status, ToWireStatus(ErrorCode::kParseError));
    EXPECT_NE(reply->message.find("record 2"), std::string::npos) << reply->message;
    EXPECT_NE(reply->message.find("runs past the end of the committed data"), std::string::npos)
        << reply->message;
  }

  // Nobody speaks for the session any more: closed after the timeout, segment removed.
  const std::string channel = protocol::SessionReplyChannel(writer->session_id);
  auto closing = (*listener)->WaitFor(
      [&](const Received& r) {
        if (r.channel != channel) return false;
        auto error = DecodeError(r.bytes);
        return error && error->session_closed;
      },
      5s);
  ASSERT_TRUE(closing.has_value()) << "no session_closed error_t for the dead client's session";
  EXPECT_TRUE(protocol::VerifyEncoded(closing->bytes, writer->key).ok());
  EXPECT_TRUE(WaitUntil([&] { return !ShmExists(writer->shm_name); }, 3s))
      << writer->shm_name << " remains";
  EXPECT_FALSE(SessionListed(writer->session_id));
  EXPECT_TRUE(daemon->Running());
  EXPECT_TRUE(HealthyClientSteps());
}

INSTANTIATE_TEST_SUITE_P(Modes, KilledClientTest,
                         ::testing::Values("unpublished", "index-mid-record", "killed"),
                         [](const auto& info) {
                           std::string name = info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST_F(SessionLifetimeTest, DaemonKilledAndRestartedLeavesNoStaleSegmentsAndServesNewSessions) {
  DaemonProcess* first = StartDaemon();
  ASSERT_NE(first, nullptr);
  auto old_client = client::Client::Connect(TestClientOptions("before-crash", 1500ms));
  ASSERT_TRUE(old_client.ok()) << far::ToString(old_client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*old_client)->LoadScene(scene).ok());
  // The first step of a session makes its pipeline: give it time on a loaded machine (the
  // short timeout is for the step after the crash).
  auto first_step = (*old_client)->StepAsync(SmallRequest());
  ASSERT_EQ(first_step.wait_for(10s), std::future_status::ready);
  ASSERT_TRUE(first_step.get().ok());
  const std::string old_shm = (*old_client)->shm_name();
  const pid_t old_pid = first->pid();

  // SIGKILL: the daemon cannot clean up; its segment stays behind.
  first->Kill();
  EXPECT_TRUE(ShmExists(old_shm)) << "a SIGKILLed daemon's segment should still be in /dev/shm";

  // The client notices: its next step times out with a message that names the daemon.
  auto step = (*old_client)->Step(SmallRequest());
  ASSERT_FALSE(step.ok());
  EXPECT_EQ(step.error().code, ErrorCode::kTimeout);
  EXPECT_NE(step.error().message.find("far-daemon"), std::string::npos) << step.error().message;

  // A new daemon removes the dead one's segments at start-up.
  DaemonProcess* second = StartDaemon();
  ASSERT_NE(second, nullptr);
  EXPECT_FALSE(ShmExists(old_shm)) << old_shm << " survived the restart";
  EXPECT_TRUE(ShmSegmentsOf(old_pid).empty());
  // (Which daemon removed it is not checked: with ctest -j, another test's daemon starting
  // in the meantime removes the dead daemon's segments too; alone, the log of this one says
  // event=stale_segments_removed.)

  // New sessions work, while the old client (still alive, still sending heartbeats for a
  // session the new daemon never made) is around.
  auto new_client = client::Client::Connect(TestClientOptions("after-restart"));
  ASSERT_TRUE(new_client.ok()) << far::ToString(new_client.error());
  ASSERT_TRUE((*new_client)->LoadScene(scene).ok());
  auto result = (*new_client)->Step(SmallRequest());
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  EXPECT_EQ(result->contacts, ReferenceContacts(scene.objects));
  EXPECT_TRUE(HealthyClientSteps());

  // A graceful stop with a session open removes its segment too.
  const std::string new_shm = (*new_client)->shm_name();
  StopDaemon(*second);
  EXPECT_FALSE(ShmExists(new_shm));
  EXPECT_TRUE(ShmSegmentsOf(second->pid()).empty());
}

TEST_F(SessionLifetimeTest, GracefulStopTellsConnectedClientsAtOnce) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  auto client = client::Client::Connect(TestClientOptions("until-the-end", 5s));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*client)->LoadScene(scene).ok());
  ASSERT_TRUE((*client)->Step(SmallRequest()).ok());
  const std::string shm = (*client)->shm_name();
  StopDaemon(*daemon);
  EXPECT_FALSE(ShmExists(shm));
  // The client learns that its session is gone without waiting for a step to time out.
  EXPECT_TRUE(WaitUntil([&] { return !(*client)->Heartbeat().ok(); }, 2s))
      << "the client was not told that the daemon closed its session";
  const auto start = std::chrono::steady_clock::now();
  auto step = (*client)->Step(SmallRequest());
  ASSERT_FALSE(step.ok());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 1s);
  EXPECT_EQ(step.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(step.error().message.find("shutting down"), std::string::npos) << step.error().message;
}

TEST_F(SessionLifetimeTest, ConnectingWithoutADaemonIsUnavailable) {
  auto client = client::Client::Connect(TestClientOptions("lonely", 1000ms));
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(client.error().message.find("no far-daemon answered"), std::string::npos)
      << client.error().message;
  const ProcessResult ping = RunFarClient({"--timeout-ms", "500", "ping"});
  EXPECT_NE(ping.exit_code, 0);
  EXPECT_NE(ping.err.find("no far-daemon answered"), std::string::npos) << ping.err;
}

}  // namespace
}  // namespace far::integration
