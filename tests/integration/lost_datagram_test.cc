// A lost LCM datagram costs a client about a second, not its timeout: the client asks again for
// a step the daemon has not acknowledged, or whose reply has not come, and the daemon answers a
// repeat from what it kept, never running a step twice (docs/protocol.md, "Lost datagrams").
// The tests lose requests, statuses and replies on purpose at the client library's loss seam
// (internal::SetDatagramLoss), against a real daemon. And a client that the daemon cannot hear
// at all (another network namespace) says so within about a second, at Connect.

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/client/internal/client_access.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using client::internal::Datagram;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Every test sets the seam and clears it when it ends, whatever fails.
class LostDatagramTest : public DaemonTest {
 protected:
  void TearDown() override {
    client::internal::SetDatagramLoss({});
    DaemonTest::TearDown();
  }

  // A session with a small soup, ready to step.
  std::unique_ptr<client::Client> Soup(const std::string& name,
                                       std::chrono::milliseconds timeout = 10s) {
    auto client = client::Client::Connect(TestClientOptions(name, timeout));
    EXPECT_TRUE(client.ok()) << far::ToString(client.error());
    if (!client) return nullptr;
    for (const SceneObject& object : ContactSoup(3)) {
      EXPECT_TRUE((*client)->AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
    }
    return std::move(*client);
  }

  // The daemon's count of steps it ran and answered.
  int64_t StepsRun() {
    auto status = client::Client::Status(TestClientOptions("status"));
    EXPECT_TRUE(status.ok()) << far::ToString(status.error());
    return status ? status->steps_total : -1;
  }
};

StepRequest AabbRequest() {
  StepRequest request;
  request.method = Method::kAabb;
  return request;
}

// Loses the first `count` messages of `kind` about step `step_id` in one direction.
std::function<bool(const Datagram&)> LoseFirst(bool outgoing, std::string kind, int64_t step_id,
                                               int count = 1) {
  auto left = std::make_shared<std::atomic<int>>(count);
  return [=](const Datagram& d) {
    if (d.outgoing != outgoing || d.kind != kind || d.step_id != step_id) return false;
    return left->fetch_sub(1) > 0;
  };
}

TEST_F(LostDatagramTest, AStepWhoseRequestIsLostIsSentAgainAndCompletesWithinASecond) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto client = Soup("lost-request");
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->Step(AabbRequest()).ok());  // step 0: the pipeline is made
  const int64_t before = StepsRun();
  client::internal::SetDatagramLoss(LoseFirst(true, "request", 1));
  const auto start = Clock::now();
  auto result = client->Step(AabbRequest());
  const double seconds = SecondsSince(start);
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  EXPECT_FALSE(result->contacts.empty());
  EXPECT_LT(seconds, 1.5) << "the lost request was not sent again in time";
  EXPECT_EQ(StepsRun() - before, 1);
}

// The reply is lost after the daemon ran the step: the client asks again after a quiet second,
// and the daemon sends the reply it kept. The step ran once.
TEST_F(LostDatagramTest, AStepWhoseReplyIsLostIsAnsweredAgainFromWhatTheDaemonKept) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto client = Soup("lost-reply");
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->Step(AabbRequest()).ok());
  const int64_t before = StepsRun();
  client::internal::SetDatagramLoss(LoseFirst(false, "reply", 1));
  const auto start = Clock::now();
  auto result = client->Step(AabbRequest());
  const double seconds = SecondsSince(start);
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  EXPECT_FALSE(result->contacts.empty());
  EXPECT_LT(seconds, 2.0) << "the lost reply was not asked for again in time";
  EXPECT_EQ(StepsRun() - before, 1) << "the step ran more than once";
}

// A reply too large for one datagram travels as a stub naming a record of the reply ring: a
// lost stub, sent again, still finds its record.
TEST_F(LostDatagramTest, ALostStubOfALargeReplyIsSentAgainAndItsRecordRead) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto client = Soup("lost-stub");
  ASSERT_NE(client, nullptr);
  StepRequest request;
  request.method = Method::kBvh;
  request.distance = 1.0;  // many distance pairs: a reply through the reply ring
  request.output = Output::kDistancePairs;
  auto first = client->Step(request);
  ASSERT_TRUE(first.ok()) << far::ToString(first.error());
  // (32 bytes per distance pair on the wire: over 63 KiB, the reply goes through the ring)
  ASSERT_GT(first->distance_pairs.size(), 63u * 1024 / 32) << "the reply would go inline";
  client::internal::SetDatagramLoss(LoseFirst(false, "reply", 1));
  const auto start = Clock::now();
  auto second = client->Step(request);
  ASSERT_TRUE(second.ok()) << far::ToString(second.error());
  EXPECT_LT(SecondsSince(start), 2.0);
  EXPECT_EQ(second->distance_pairs, first->distance_pairs);
}

// A third of everything lost, both ways, at random (seeded): every step completes, each within
// a few seconds, and none runs twice.
TEST_F(LostDatagramTest, EveryStepCompletesOnceWhenAThirdOfAllMessagesAreLost) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto client = Soup("lossy");
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->Step(AabbRequest()).ok());
  const int64_t before = StepsRun();
  const int64_t session = client->session_id();
  auto random = std::make_shared<std::mt19937>(41);
  auto mutex = std::make_shared<std::mutex>();
  client::internal::SetDatagramLoss([=](const Datagram& d) {
    if (d.session_id != session) return false;
    std::lock_guard lock(*mutex);
    return (*random)() % 3 == 0;
  });
  constexpr int kSteps = 20;
  double worst = 0;
  for (int i = 0; i < kSteps; ++i) {
    const auto start = Clock::now();
    auto result = client->Step(AabbRequest());
    ASSERT_TRUE(result.ok()) << "step " << i + 1 << ": " << far::ToString(result.error());
    worst = std::max(worst, SecondsSince(start));
  }
  client::internal::SetDatagramLoss({});
  // (a request and its answer both get through 4 times in 9: a few tries in a row can fail)
  EXPECT_LT(worst, 6.0);
  std::printf("worst step of %d with a third of all messages lost: %.2f s\n", kSteps, worst);
  EXPECT_EQ(StepsRun() - before, kSteps) << "a step ran more than once, or not at all";
}

// Past its limit, a step the daemon never acknowledged says so (not "raise the timeout").
TEST_F(LostDatagramTest, AStepNeverAcknowledgedSaysSoAtTheClientsLimit) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto client = Soup("unheard", 1500ms);
  ASSERT_NE(client, nullptr);
  client::internal::SetDatagramLoss(LoseFirst(true, "request", 0, 1000));
  const auto start = Clock::now();
  auto result = client->Step(AabbRequest());
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kTimeout);
  EXPECT_NE(result.error().message.find("step 0 was never acknowledged within 1500 ms"),
            std::string::npos)
      << result.error().message;
  EXPECT_EQ(result.error().message.find("raise the timeout"), std::string::npos);
  EXPECT_LT(SecondsSince(start), 3.0);
}

// The daemon answers a repeated step id from what it kept: the same reply, and the step is not
// run again. Through the protocol directly, as any client would send it.
TEST_F(LostDatagramTest, TheDaemonAnswersARepeatedStepIdWithItsKeptReplyAndRunsItOnce) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "repeat");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  for (const SceneObject& o : ContactSoup(3))
    ASSERT_TRUE((*raw)->writer().AddObject(o.id, o.mesh, o.motion, o.X_WO).ok());
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kAabb)).ok());
  auto first = (*raw)->WaitStepReply(0);
  ASSERT_TRUE(first.has_value());
  ASSERT_EQ(first->status, 0) << first->message;
  const int64_t before = StepsRun();
  // Asked again (a new request id, the same step id), with another update in the ring.
  ASSERT_TRUE((*raw)->writer().RemoveObject(ContactSoup(3).front().id).ok());
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kAabb)).ok());
  auto again = (*raw)->WaitStepReply(0);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->request_id, first->request_id);
  EXPECT_EQ(again->num_contacts, first->num_contacts);
  EXPECT_EQ(again->ring_applied_sequence, first->ring_applied_sequence) << "the step ran again";
  EXPECT_EQ(StepsRun(), before);
  // An older step id than any kept answer is refused, not run.
  for (int64_t step = 1; step <= 5; ++step) {
    ASSERT_TRUE((*raw)->SendStep(step, SmallRequest(Method::kAabb)).ok());
    ASSERT_TRUE((*raw)->WaitStepReply(step).has_value());
  }
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kAabb)).ok());
  auto forgotten = (*raw)->WaitStepReply(0);
  ASSERT_TRUE(forgotten.has_value());
  EXPECT_EQ(forgotten->status, protocol::ToWireStatus(ErrorCode::kNotFound));
  EXPECT_NE(forgotten->message.find("step 0 was answered before the last 4 answers"),
            std::string::npos)
      << forgotten->message;
}

// A probe, sent by the client at open, is answered at once with a status "heard"; repeats and
// probes beyond the session's repeat rate are dropped unanswered.
TEST_F(LostDatagramTest, ProbesAreAnsweredHeardWithinTheSessionsRepeatRate) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "prober");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  constexpr int kProbes = 60;  // in a burst: the rate is 20/s, 20 at once
  for (int i = 0; i < kProbes; ++i) {
    auto bytes = protocol::EncodeSigned(
        protocol::MakeProbeRequest((*raw)->id(), (*raw)->NextRequestId()), (*raw)->key());
    ASSERT_TRUE(bytes.ok());
    ASSERT_TRUE((*raw)->PublishRequest(*bytes).ok());
  }
  int heard = 0;
  while ((*raw)->WaitReply(
      [](const ReplyMessage& m) { return m.status && m.status->state == "heard"; }, 1s)) {
    ++heard;
  }
  EXPECT_GE(heard, 20);
  EXPECT_LT(heard, kProbes);
}

TEST_F(LostDatagramTest, ALostProbeIsSentAgainAndTheSessionOpens) {
  ASSERT_NE(StartDaemon(), nullptr);
  client::internal::SetDatagramLoss([](const Datagram& d) {
    static std::atomic<int> lost{0};
    return d.outgoing && d.kind == "probe" && lost.fetch_add(1) < 2;
  });
  const auto start = Clock::now();
  auto client = client::Client::Connect(TestClientOptions("probe-lost"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  EXPECT_LT(SecondsSince(start), 1.0);
  EXPECT_TRUE((*client)->Step(AabbRequest()).ok());
}

// `far-client load` in a network namespace of its own, its daemon in this one: the socket
// reaches the daemon, LCM does not. The client says so within about a second, naming the
// cause (it waited its whole 60 s timeout, and then blamed the scene's size).
TEST_F(LostDatagramTest, AClientInAnotherNetworkNamespaceIsToldWithinASecond) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  const auto start = Clock::now();
  const ProcessResult run = RunProcess(
      {"/usr/bin/unshare", "-n", "/bin/bash", "-c",
       "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && "
       "exec \"$@\"",
       "netns", FAR_CLIENT_PATH, "--socket", daemon->socket_path(), "load", "--seconds", "6",
       "--clients", "1"},
      90s);
  const double seconds = SecondsSince(start);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_LT(seconds, 5.0) << run.out << run.err;
  const std::string said = run.out + run.err;
  EXPECT_NE(said.find("opened this session but hears none of its steps over LCM"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("It runs in another network namespace"), std::string::npos) << said;
  EXPECT_EQ(said.find("raise the timeout"), std::string::npos) << said;
}

// The default socket's daemon cannot hear this client (it runs in another network namespace),
// but a daemon of the same name in the next socket directory can: the client opens its session
// there (the socket directories' order: docs/daemon.md, "Where it listens").
TEST_F(LostDatagramTest, AClientNotHeardAtTheFirstSocketOpensAtTheNextOneOfTheSameName) {
  struct stat info {};
  if (::getenv("FAR_SOCKET_DIR") != nullptr || stat("/run/far", &info) == 0) {
    GTEST_SKIP() << "needs $XDG_RUNTIME_DIR/far first in the socket order: unset FAR_SOCKET_DIR "
                    "and run where /run/far does not exist";
  }
  TempDir runtime;
  const std::string name = "lost" + std::to_string(::getpid() % 100000);
  ::setenv("XDG_RUNTIME_DIR", runtime.path().c_str(), 1);
  const std::vector<std::string> dirs = protocol::SocketDirectories();
  ASSERT_EQ(dirs.size(), 2u);
  // The deaf one: at $XDG_RUNTIME_DIR/far/<name>.sock, in a network namespace of its own.
  const std::string deaf_socket = dirs[0] + "/" + name + ".sock";
  auto deaf = ChildProcess::Spawn(
      {"/usr/bin/unshare", "-n", "/bin/bash", "-c",
       "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && "
       "exec \"$@\" > /dev/null 2>&1",
       "netns", FAR_DAEMON_PATH, "--name", name, "--socket", deaf_socket});
  ASSERT_TRUE(deaf.ok()) << far::ToString(deaf.error());
  client::ClientOptions probe;
  probe.socket_path = deaf_socket;
  probe.connect_timeout = 20s;
  ASSERT_TRUE(client::Client::Status(probe).ok()) << "the deaf daemon did not start";
  // The one meant: at /tmp/far-<uid>/<name>.sock, in this namespace.
  ASSERT_NE(StartDaemon({"--name", name, "--socket", dirs[1] + "/" + name + ".sock"}), nullptr);
  client::ClientOptions options;
  options.daemon = name;
  options.timeout = 10s;
  auto client = client::Client::Connect(options);
  ::unsetenv("XDG_RUNTIME_DIR");
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  EXPECT_TRUE((*client)->Step(AabbRequest()).ok());
}

}  // namespace
}  // namespace far::integration
