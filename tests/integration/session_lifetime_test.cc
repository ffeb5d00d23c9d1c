// How sessions end: a client that exits or is killed (its connection to the daemon closes, and
// the session goes at once, even in the middle of a step), a daemon killed with SIGKILL and
// started again, a daemon stopped gracefully, and no daemon at all, or not yet.
#include <signal.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <future>
#include <sstream>
#include <thread>
#include <vector>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;

bool SessionListed(int64_t id) {
  auto status = client::Client::Status(TestClientOptions("status"));
  if (!status) return true;  // unknown: treat as "still there" so the check fails loudly
  return std::any_of(status->sessions.begin(), status->sessions.end(),
                     [&](const auto& s) { return s.id == id; });
}

bool Mapped(pid_t daemon, const std::string& segment) {
  const auto mapped = SessionSegmentsOf(daemon);
  return std::find(mapped.begin(), mapped.end(), segment) != mapped.end();
}

using SessionLifetimeTest = DaemonTest;

TEST_F(SessionLifetimeTest, AClientThatGoesAwayEndsItsSessionAtOnceAndASilentOneStays) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  auto leaving = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "leaving");
  auto silent = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "silent");
  ASSERT_TRUE(leaving.ok()) << far::ToString(leaving.error());
  ASSERT_TRUE(silent.ok()) << far::ToString(silent.error());
  const std::string segment = (*leaving)->segment().name();
  ASSERT_TRUE(Mapped(daemon->pid(), segment));
  EXPECT_TRUE(SessionListed((*leaving)->id()));

  (*leaving)->Disconnect();
  EXPECT_TRUE(WaitUntil([&] { return !Mapped(daemon->pid(), segment); }, 2s))
      << segment << " is still mapped by the daemon after its client left";
  EXPECT_FALSE(SessionListed((*leaving)->id()));

  // A client that is alive but quiet keeps its session: there are no heartbeats to miss.
  std::this_thread::sleep_for(1500ms);
  EXPECT_TRUE(SessionListed((*silent)->id()));
  ASSERT_TRUE((*silent)->writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE((*silent)->SendStep(0, SmallRequest()).ok());
  auto reply = (*silent)->WaitStepReply(0);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, 0) << reply->message;

  // The gone session's requests are now for an unknown session: dropped, unanswered.
  (*leaving)->listener().Clear();
  ASSERT_TRUE((*leaving)->SendStep(0, SmallRequest()).ok());
  EXPECT_FALSE((*leaving)->WaitStepReply(0, 500ms).has_value());
  EXPECT_TRUE(HealthyClientSteps());
}

// A child (this binary in --far-half-writer mode) opens a session and dies while writing.
struct DeadWriter {
  int64_t session_id = 0;
  std::string segment;
};

std::optional<DeadWriter> ReadWriterLine(ChildProcess& child) {
  auto line = child.ReadLine(10s);
  if (!line) return std::nullopt;
  DeadWriter writer;
  std::istringstream in(*line);
  std::string key_hex;
  in >> writer.session_id >> writer.segment >> key_hex;
  if (!in || key_hex.size() != 64) return std::nullopt;
  return writer;
}

class KilledClientTest : public DaemonTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(KilledClientTest, TheSessionOfAClientThatDiesWritingIsClosedAtOnce) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  const std::string mode = GetParam();
  auto child = ChildProcess::Spawn({SelfPath(), "--far-half-writer", mode, CurrentSocketPath()});
  ASSERT_TRUE(child.ok()) << far::ToString(child.error());
  auto writer = ReadWriterLine(**child);
  ASSERT_TRUE(writer.has_value()) << "the half-writer did not report its session";
  if (mode == "killed") {
    std::this_thread::sleep_for(300ms);
    EXPECT_EQ((*child)->Kill(), 128 + SIGKILL);
  } else {
    EXPECT_EQ((*child)->Wait(10s), std::optional<int>(0));
  }
  // Its connection closed with it: the session is gone and its segment unmapped.
  EXPECT_TRUE(WaitUntil([&] { return !Mapped(daemon->pid(), writer->segment); }, 2s))
      << writer->segment << " remains";
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

TEST_F(SessionLifetimeTest, AClientThatLeavesMidStepHasItsStepCancelledAndItsSessionFreed) {
  // Statuses at once: the test waits for the exact stage's (status_after_ms would skip a stage
  // that starts within 5 ms of the request).
  DaemonProcess* daemon = StartDaemon({"--status-after-ms", "0"});
  ASSERT_NE(daemon, nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "impatient");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  // Two coplanar grids of 2 x 120^2 = 28,800 triangles: the brute force tests 8e8 pairs, many
  // seconds of work on two cores.
  ASSERT_TRUE((*raw)->writer().AddObject(1, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->writer().AddObject(2, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kExact)).ok());
  auto started = (*raw)->WaitReply(
      [](const ReplyMessage& m) { return m.status && m.status->stage == "exact"; }, 20s);
  ASSERT_TRUE(started.has_value()) << "the step never reached its exact stage";
  const std::string segment = (*raw)->segment().name();
  const auto left = std::chrono::steady_clock::now();
  (*raw)->Disconnect();
  // The session goes while its step would still be running: the step was cancelled inside its
  // exact stage (the daemon logs why the step ended).
  EXPECT_TRUE(WaitUntil([&] { return !Mapped(daemon->pid(), segment); }, 5s))
      << segment << " is still mapped: the step was not cancelled";
  EXPECT_LT(std::chrono::steady_clock::now() - left, 5s);
  EXPECT_TRUE(WaitUntil(
      [&] {
        return daemon->Log().find("step cancelled by its caller (during exact)") !=
               std::string::npos;
      },
      2s))
      << "the log does not say that the step was cancelled in its exact stage";
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(SessionLifetimeTest, ALeavingClientsSegmentMemoryGoesAtOnceWhileItsStepRunsOn) {
  // Issue 41: a killed client's segment stayed allocated until its running step had ended (22 s
  // behind GL views; a GL view does not stop when the session is cancelled). The daemon now
  // frees the segment's memory the moment the connection closes, and unmaps the emptied segment
  // when the step has ended. The test keeps a descriptor of the segment, as a hoarder would: it
  // must hold nothing either.
  DaemonProcess* daemon = StartDaemon({"--status-after-ms", "0"});  // it waits for a status
  ASSERT_NE(daemon, nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "leaving-mid-view");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  // Two coplanar grids of 2 x 60^2 = 7,200 triangles, FAR at 512^2: a primitive_cull stage of
  // seconds on llvmpipe (2 cores), whose GL views run to their end.
  ASSERT_TRUE((*raw)->writer().AddObject(1, FlatGrid(60), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->writer().AddObject(2, FlatGrid(60), Motion::kStatic, Pose{}).ok());
  StepRequest request = SmallRequest(Method::kFar);
  request.resolution = 512;
  ASSERT_TRUE((*raw)->SendStep(0, request).ok());
  auto culling = (*raw)->WaitReply(
      [](const ReplyMessage& m) { return m.status && m.status->stage == "primitive_cull"; }, 30s);
  ASSERT_TRUE(culling.has_value()) << "the step never reached its primitive_cull stage";
  const int fd = (*raw)->segment_fd();
  struct stat info {};
  ASSERT_EQ(fstat(fd, &info), 0);
  ASSERT_GT(info.st_blocks, 0);
  const std::string segment = (*raw)->segment().name();
  const auto left = std::chrono::steady_clock::now();
  (*raw)->Disconnect();
  const bool freed = WaitUntil([&] { return fstat(fd, &info) == 0 && info.st_blocks == 0; }, 1s);
  const double freed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - left).count();
  const bool still_mapped = Mapped(daemon->pid(), segment);
  EXPECT_TRUE(freed) << info.st_blocks * 512 << " bytes still allocated 1 s after the client left";
  EXPECT_TRUE(WaitUntil([&] { return !Mapped(daemon->pid(), segment); }, 60s));
  std::printf("segment memory freed after %.3f s (the daemon %s); unmapped after %.3f s\n", freed_s,
              still_mapped ? "still mapped it: the step ran on" : "had unmapped it",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - left).count());
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(SessionLifetimeTest, DaemonKilledAndRestartedTellsOldClientsAndServesNewSessions) {
  DaemonProcess* first = StartDaemon();
  ASSERT_NE(first, nullptr);
  const std::string socket = first->socket_path();
  auto old_client = client::Client::Connect(TestClientOptions("before-crash"));
  ASSERT_TRUE(old_client.ok()) << far::ToString(old_client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*old_client)->LoadScene(scene).ok());
  ASSERT_TRUE((*old_client)->Step(SmallRequest()).ok());

  // SIGKILL: the daemon cannot say goodbye; its clients see their connection close.
  first->Kill();
  const auto start = std::chrono::steady_clock::now();
  auto step = (*old_client)->Step(SmallRequest());
  ASSERT_FALSE(step.ok());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s) << "the client waited for a dead daemon";
  EXPECT_EQ(step.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(step.error().message.find("far-daemon"), std::string::npos) << step.error().message;

  // A new daemon takes over the dead one's socket, and new sessions work.
  DaemonProcess* second = StartDaemon({"--socket", socket});
  ASSERT_NE(second, nullptr);
  auto new_client = client::Client::Connect(TestClientOptions("after-restart"));
  ASSERT_TRUE(new_client.ok()) << far::ToString(new_client.error());
  ASSERT_TRUE((*new_client)->LoadScene(scene).ok());
  auto result = (*new_client)->Step(SmallRequest());
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  EXPECT_EQ(result->contacts, ReferenceContacts(scene.objects));
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(SessionLifetimeTest, GracefulStopTellsConnectedClientsAtOnce) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  auto client = client::Client::Connect(TestClientOptions("until-the-end"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*client)->LoadScene(scene).ok());
  ASSERT_TRUE((*client)->Step(SmallRequest()).ok());
  StopDaemon(*daemon);
  const auto start = std::chrono::steady_clock::now();
  auto step = (*client)->Step(SmallRequest());
  ASSERT_FALSE(step.ok());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 1s);
  EXPECT_EQ(step.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(step.error().message.find("shutting down"), std::string::npos) << step.error().message;
}

// A daemon stopped while clients open sessions as fast as they can exits cleanly. It used to
// crash now and then: the socket thread logged a new session after starting its worker, and the
// shutdown's reaping had that worker free the session's segment under the log line.
TEST_F(SessionLifetimeTest, StoppingWhileSessionsOpenExitsCleanly) {
  constexpr int kRounds = 4, kOpeners = 4;
  for (int round = 0; round < kRounds; ++round) {
    DaemonProcess* daemon = StartDaemon({"--max-opens-per-second", "100000"});
    ASSERT_NE(daemon, nullptr);
    client::ClientOptions options = TestClientOptions("opener");
    options.connect_timeout = 100ms;
    std::atomic<bool> done{false};
    std::atomic<int> opened{0};
    std::vector<std::thread> openers;
    for (int i = 0; i < kOpeners; ++i) {
      openers.emplace_back([&] {
        // Each opener holds its newest session, so that some are open when the stop comes.
        std::unique_ptr<client::Client> held;
        while (!done) {
          auto client = client::Client::Connect(options);
          if (client.ok()) {
            held = std::move(*client);
            ++opened;
          }
        }
      });
    }
    EXPECT_TRUE(WaitUntil([&] { return opened >= 20; }, 10s)) << "opened " << opened;
    StopDaemon(*daemon);
    done = true;
    for (std::thread& opener : openers) opener.join();
    if (HasFailure()) break;
  }
}

TEST_F(SessionLifetimeTest, NoDaemonIsSaidWithinAboutASecond) {
  client::ClientOptions options = TestClientOptions("lonely");
  options.socket_path = "/tmp/far-no-such-daemon/far.sock";
  const auto start = std::chrono::steady_clock::now();
  auto client = client::Client::Connect(options);
  ASSERT_FALSE(client.ok());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
  EXPECT_EQ(client.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(client.error().message.find("no far-daemon named 'far' is running"), std::string::npos)
      << client.error().message;
  const ProcessResult ping = RunFarClient({"--socket", options.socket_path, "ping"});
  EXPECT_NE(ping.exit_code, 0);
  EXPECT_NE(ping.err.find("no far-daemon named 'far' is running"), std::string::npos) << ping.err;
}

TEST_F(SessionLifetimeTest, AClientStartedBeforeItsDaemonWaitsForIt) {
  // The client starts first and retries with backoff; the daemon comes up 400 ms later.
  TempDir dir;
  const std::string socket = (dir.path() / "far.sock").string();
  auto ping = std::async(std::launch::async, [&] {
    return RunFarClient({"--socket", socket, "--connect-timeout", "10s", "ping"});
  });
  std::this_thread::sleep_for(400ms);
  ASSERT_NE(StartDaemon({"--socket", socket}), nullptr);
  const ProcessResult result = ping.get();
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("answered"), std::string::npos) << result.out;
}

}  // namespace
}  // namespace far::integration
