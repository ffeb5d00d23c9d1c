// Per-user limits of the daemon's socket, keyed by the uid the kernel reports (SO_PEERCRED):
// the sessions one user may hold (max_sessions_per_user), how fast they may open them
// (max_opens_per_second_per_user), and that another user is still served, and sees only its own
// sessions in status, while one user holds all it may.
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <latch>
#include <map>
#include <sstream>
#include <thread>

#include "daemon_fixture.h"
#include "healthy_session.h"
#include "integration_scenes.h"
#include "other_user_client.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;

// The uid of the other user (Debian's "nobody").
using UserLimitsTest = DaemonTest;

TEST_F(UserLimitsTest, AUserOverItsSessionLimitIsRefusedWhileItsSessionsWork) {
  ASSERT_NE(StartDaemon({"--max-sessions-per-user", "3"}), nullptr);
  std::vector<std::unique_ptr<client::Client>> mine;
  for (int i = 0; i < 3; ++i) mine.push_back(HealthySession("mine-" + std::to_string(i)));
  for (const auto& client : mine) ASSERT_NE(client, nullptr);

  // The fourth: refused with the limit's name, though the daemon has room for 64.
  auto fourth = client::Client::Connect(TestClientOptions("one-too-many"));
  ASSERT_FALSE(fourth.ok());
  EXPECT_EQ(fourth.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(fourth.error().message.find("max_sessions_per_user: user " + std::to_string(geteuid()) +
                                        " has 3 sessions open"),
            std::string::npos)
      << fourth.error().message;
  // The three go on as if nothing happened.
  for (const auto& client : mine) EXPECT_TRUE(StepsWithTheReference(*client));

  // One closed, the user may open one again.
  ASSERT_TRUE(mine.back()->Close().ok());
  ASSERT_TRUE(WaitUntil([] { return SessionsOpen() == 2; }, 3s));
  EXPECT_NE(HealthySession("again"), nullptr);
}

// Several simulators of one user started together (or `far-client load --clients 6`) connect
// before the daemon has heard what any of them wants: every one of them is served, up to the
// sessions the user may hold. The daemon used to drop the fifth connection waiting at once.
TEST_F(UserLimitsTest, ClientsOfOneUserThatConnectAtOnceAreAllServed) {
  ASSERT_NE(StartDaemon(), nullptr);  // 16 sessions per user, opens in bursts of 20
  constexpr int kClients = 12;
  std::latch start(kClients);
  std::vector<std::string> failures(kClients);
  std::vector<std::thread> threads;
  for (int i = 0; i < kClients; ++i) {
    threads.emplace_back([&, i] {
      start.arrive_and_wait();
      auto client = client::Client::Connect(TestClientOptions("burst-" + std::to_string(i)));
      if (!client) {
        failures[i] = far::ToString(client.error());
        return;
      }
      Scene scene;
      scene.objects = ContactSoup(kHealthySeed);
      if (auto loaded = (*client)->LoadScene(scene); !loaded) {
        failures[i] = far::ToString(loaded.error());
        return;
      }
      if (auto stepped = StepsWithTheReference(**client); !stepped) {
        failures[i] = stepped.message();
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int i = 0; i < kClients; ++i) EXPECT_EQ(failures[i], "") << "client " << i;
}

TEST_F(UserLimitsTest, OpeningFasterThanTheOpenRateIsBusyAndTheRateRefills) {
  // One open every 2 s, a burst of one: the second open at once is over the rate, whatever the
  // machine's speed.
  ASSERT_NE(StartDaemon({"--max-opens-per-second", "0.5"}), nullptr);
  auto first = HealthySession("first");
  ASSERT_NE(first, nullptr);
  auto second = client::Client::Connect(TestClientOptions("too-soon"));
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.error().code, ErrorCode::kBusy);
  EXPECT_NE(
      second.error().message.find("max_opens_per_second_per_user: user " +
                                  std::to_string(geteuid()) + " opens sessions faster than 0.5/s"),
      std::string::npos)
      << second.error().message;
  EXPECT_TRUE(StepsWithTheReference(*first));
  // The bucket refills at the rate: after 2 s there is a token again.
  std::this_thread::sleep_for(2100ms);
  EXPECT_NE(HealthySession("later"), nullptr);
}

// What the other user's client printed (other_user_client.h).
struct OtherUserReport {
  int uid = -1;
  size_t contacts = 0;
  std::vector<client::DaemonStatus::Session> sessions;  // uid, client_name, triangles
  int sessions_open = -1;
};

std::optional<OtherUserReport> ReadReport(ChildProcess& child, std::string* failure) {
  OtherUserReport report;
  while (auto line = child.ReadLine(20s)) {
    std::istringstream in(*line);
    std::string tag;
    in >> tag;
    if (tag == "stepped") {
      in >> report.uid >> report.contacts;
    } else if (tag == "session") {
      client::DaemonStatus::Session session;
      in >> session.uid >> session.client_name >> session.triangles;
      report.sessions.push_back(session);
    } else if (tag == "end") {
      in >> report.sessions_open;
      return report;
    } else {
      *failure = *line;
      return std::nullopt;
    }
  }
  *failure = "no report (the child printed nothing more)";
  return std::nullopt;
}

// max_requests_per_second holds requests sent without waiting for the answers; a client that
// waits for each answer is never refused for its rate, however fast its steps come (a small
// scene stepped back to back: well over 20 per second here, thousands by default).
TEST_F(UserLimitsTest, AClientThatWaitsForEachAnswerIsNeverRefusedForItsRate) {
  ASSERT_NE(StartDaemon({"--max-rate", "20"}), nullptr);
  auto client = HealthySession("synchronous");
  ASSERT_NE(client, nullptr);
  const auto start = std::chrono::steady_clock::now();
  for (int step = 0; step < 100; ++step) ASSERT_TRUE(StepsWithTheReference(*client)) << step;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 100 / 20.0) << "the steps came slower than the rate: nothing was tested";
}

TEST_F(UserLimitsTest, RequestsSentWithoutWaitingAreHeldToTheRate) {
  // A queue long enough that only the rate refuses: 60 requests at once, a bucket of 8.
  TempDir dir;
  const auto config = dir.path() / "far.json";
  {
    std::ofstream out(config);
    out << R"({"max_requests_per_second": 20, "max_queued_per_session": 100})";
  }
  ASSERT_NE(StartDaemon({"--config", config.string()}), nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "eager");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  ASSERT_TRUE((*raw)->writer().AddObject(1, TriangleRow(20), Motion::kRigid, Pose{}).ok());
  constexpr int kSteps = 60;
  for (int step = 0; step < kSteps; ++step)
    ASSERT_TRUE((*raw)->SendStep(step, SmallRequest()).ok());
  int ok = 0, over_rate = 0;
  for (int step = 0; step < kSteps; ++step) {
    auto reply = (*raw)->WaitStepReply(step);
    ASSERT_TRUE(reply.has_value()) << "no reply to step " << step;
    if (reply->status == 0) {
      ++ok;
      continue;
    }
    EXPECT_EQ(reply->status, protocol::ToWireStatus(ErrorCode::kBusy)) << reply->message;
    EXPECT_NE(reply->message.find("over its request rate (20/s)"), std::string::npos)
        << reply->message;
    ++over_rate;
  }
  EXPECT_GT(ok, 0);
  EXPECT_GT(over_rate, 0) << "60 requests at once should overflow a bucket of 8";
  // The session goes on: a request once the queue has drained is served.
  auto client = HealthySession("after-the-burst");
  ASSERT_NE(client, nullptr);
}

TEST_F(UserLimitsTest, AnotherUserIsServedAndSeesOnlyItsOwnSessionsWhileRootIsAtItsLimit) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to run a client as uid " << kOtherUid;
  // The other user must reach the socket: a folder it may enter (and not write to).
  TempDir dir;
  ASSERT_EQ(chmod(dir.path().c_str(), 0755), 0);
  const std::string socket = (dir.path() / "far.sock").string();
  ASSERT_NE(StartDaemon({"--socket", socket, "--max-sessions-per-user", "2"}), nullptr);
  auto root_a = HealthySession("root-a");
  auto root_b = HealthySession("root-b");
  ASSERT_NE(root_a, nullptr);
  ASSERT_NE(root_b, nullptr);
  auto third = client::Client::Connect(TestClientOptions("root-c"));
  ASSERT_FALSE(third.ok());
  EXPECT_EQ(third.error().code, ErrorCode::kLimitExceeded) << third.error().message;

  auto child = ChildProcess::Spawn({SelfPath(), "--far-other-user", socket}, kOtherUid);
  ASSERT_TRUE(child.ok()) << far::ToString(child.error());
  std::string failure;
  auto report = ReadReport(**child, &failure);
  if (!report && (*child)->Wait(2s) == ChildProcess::kCannotSwitchUser)
    GTEST_SKIP() << "cannot switch to uid " << kOtherUid << " (a user namespace without it?)";
  ASSERT_TRUE(report.has_value()) << failure;
  // Served: its step has the reference contacts.
  EXPECT_EQ(report->uid, static_cast<int>(kOtherUid));
  EXPECT_EQ(report->contacts, ReferenceContacts(ContactSoup(kHealthySeed)).size());
  // Its status: the count of all sessions, but only its own session's name and size.
  EXPECT_EQ(report->sessions_open, 3);
  ASSERT_EQ(report->sessions.size(), 1u) << "the other user sees someone else's sessions";
  EXPECT_EQ(report->sessions[0].uid, static_cast<int>(kOtherUid));
  EXPECT_EQ(report->sessions[0].client_name, kOtherUserClientName);
  EXPECT_EQ(report->sessions[0].triangles, 192);

  // Root sees every session, each with its owner and size.
  auto status = client::Client::Status(TestClientOptions("root-status"));
  ASSERT_TRUE(status.ok()) << far::ToString(status.error());
  std::map<std::string, std::pair<int, int64_t>> listed;  // name -> uid, triangles
  for (const auto& s : status->sessions) listed[s.client_name] = {s.uid, s.triangles};
  EXPECT_EQ(listed.size(), 3u);
  EXPECT_EQ(listed["root-a"], std::make_pair(0, int64_t{192}));
  EXPECT_EQ(listed["root-b"], std::make_pair(0, int64_t{192}));
  EXPECT_EQ(listed[kOtherUserClientName],
            std::make_pair(static_cast<int>(kOtherUid), int64_t{192}));
  (*child)->Kill();
  EXPECT_TRUE(StepsWithTheReference(*root_a));
}

}  // namespace
}  // namespace far::integration
