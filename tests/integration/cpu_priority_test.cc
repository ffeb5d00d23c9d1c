// A session whose step runs longer than heavy_step_ms gives way to light sessions while that
// step still runs, even when the step never finishes (it is stopped at its deadline): its
// threads drop to nice 10 under SCHED_IDLE, and a light client is served meanwhile.
#include <dirent.h>
#include <sched.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;

// How many threads of process `pid` run at nice 10 under SCHED_IDLE, the background of a heavy
// session (/proc/<pid>/task/*/stat: after "(comm)", nice is field 19 and policy field 41).
int ThreadsInBackground(pid_t pid) {
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  DIR* dir = opendir(tasks.c_str());
  if (dir == nullptr) return -1;
  int count = 0;
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    std::ifstream stat(tasks + "/" + entry->d_name + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    std::istringstream fields(text.substr(text.rfind(')') + 2));
    std::string field, nice, policy;
    for (int i = 3; i <= 41 && fields >> field; ++i) {
      if (i == 19) nice = field;
      if (i == 41) policy = field;
    }
    if (nice == "10" && policy == std::to_string(SCHED_IDLE)) ++count;
  }
  closedir(dir);
  return count;
}

using CpuPriorityTest = DaemonTest;

TEST_F(CpuPriorityTest, AStepThatRunsLongIsLoweredWhileItRunsThoughItEndsAtItsDeadline) {
  // Statuses at once: the test waits for the exact stage's, which a step whose exact stage
  // starts within status_after_ms (5 ms) of its request would not send (a fresh-clone CI run).
  DaemonProcess* daemon = StartDaemon({"--step-deadline-ms", "500", "--status-after-ms", "0"});
  ASSERT_NE(daemon, nullptr);
  ASSERT_EQ(ThreadsInBackground(daemon->pid()), 0);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "heavy");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  // Two coplanar grids of 28,800 triangles: the brute force tests 8e8 pairs, more than a second
  // of work on two cores.
  ASSERT_TRUE((*raw)->writer().AddObject(1, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->writer().AddObject(2, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kExact)).ok());
  auto exact = (*raw)->WaitReply(
      [](const ReplyMessage& m) { return m.status && m.status->stage == "exact"; }, 20s);
  ASSERT_TRUE(exact.has_value()) << "the step never reached its exact stage";
  // Within moments of passing heavy_step_ms (50), with the step still running: the session is
  // demoted, and its threads (the worker and the pool's) run at nice 10 under SCHED_IDLE.
  const std::string tag = "event=session_demoted session=" + std::to_string((*raw)->id());
  EXPECT_TRUE(WaitUntil([&] { return daemon->Log().find(tag) != std::string::npos; }, 2s))
      << "no demotion while the step runs";
  EXPECT_NE(daemon->Log().find("step=running"), std::string::npos);
  // (each thread lowers itself at its next check, a few milliseconds apart)
  const int threads = static_cast<int>(std::min(2u, std::thread::hardware_concurrency()));
  EXPECT_TRUE(WaitUntil([&] { return ThreadsInBackground(daemon->pid()) >= threads; }, 1s))
      << ThreadsInBackground(daemon->pid()) << " threads at nice 10 under SCHED_IDLE";
  // A light client is served meanwhile.
  EXPECT_TRUE(HealthyClientSteps("light"));
  auto reply = (*raw)->WaitStepReply(0, 10s);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, protocol::ToWireStatus(ErrorCode::kTimeout)) << reply->message;
  EXPECT_NE(reply->message.find("stopped at its deadline"), std::string::npos) << reply->message;
}

// The step's cost is judged before it runs: once a step ran into the daemon's deadline, the same
// request on the same scene is refused at once (the updates still applied), and another
// request runs.
TEST_F(CpuPriorityTest, AStepThatRanIntoTheDeadlineIsRefusedAtOnceWhenAskedAgain) {
  DaemonProcess* daemon = StartDaemon({"--step-deadline-ms", "500"});
  ASSERT_NE(daemon, nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "heavy");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  ASSERT_TRUE((*raw)->writer().AddObject(1, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->writer().AddObject(2, FlatGrid(120), Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE((*raw)->SendStep(0, SmallRequest(Method::kExact)).ok());
  auto first = (*raw)->WaitStepReply(0, 20s);
  ASSERT_TRUE(first.has_value());
  ASSERT_EQ(first->status, protocol::ToWireStatus(ErrorCode::kTimeout)) << first->message;

  // The same request again, with an update in the ring: refused before it runs.
  ASSERT_TRUE((*raw)->writer().AddObject(3, FlatGrid(2), Motion::kStatic, Pose{}).ok());
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE((*raw)->SendStep(1, SmallRequest(Method::kExact)).ok());
  auto second = (*raw)->WaitStepReply(1, 20s);
  ASSERT_TRUE(second.has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 400ms) << "the step ran";
  EXPECT_EQ(second->status, protocol::ToWireStatus(ErrorCode::kLimitExceeded)) << second->message;
  EXPECT_NE(second->message.find("ran into the daemon's step deadline"), std::string::npos)
      << second->message;

  // Another request on the same scene runs, and sees the object the refused step brought.
  StepRequest pcs = SmallRequest(Method::kAabb);
  pcs.output = Output::kObjectPcs;
  ASSERT_TRUE((*raw)->SendStep(2, pcs).ok());
  auto third = (*raw)->WaitStepReply(2, 20s);
  ASSERT_TRUE(third.has_value());
  EXPECT_EQ(third->status, 0) << third->message;
  EXPECT_EQ(third->ring_applied_sequence, 3);  // the three objects' records
}

// Light sessions that together saturate the machine are not heavy: contention stretches
// their steps' wall time past heavy_step_ms now and then, not the CPU time their workers spend
// on them. Judged by wall time alone, 16 clients of the paper's leaves on 2 cores were each
// demoted at a random moment, for good, and served 4.6x apart.
TEST_F(CpuPriorityTest, LightSessionsThatSaturateTheMachineTogetherAreNotDemoted) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  TempDir dir;
  const auto scene = dir.path() / "leaves" / "scene.json";
  const ProcessResult made =
      RunFarClient({"make-scene", scene.string(), "--kind", "leaves", "--frames", "40"});
  ASSERT_EQ(made.exit_code, 0) << made.out << made.err;
  const ProcessResult load =
      RunFarClient({"load", "--clients", "16", "--steps", "0", "--seconds", "4", "--method", "bvh",
                    "--scene", scene.string(), "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  const auto report = nlohmann::json::parse(load.out);
  for (const auto& client : report["per_client"]) {
    EXPECT_GT(client["steps"].get<int>(), 0) << client.dump();
    EXPECT_EQ(client["errors"].get<int>(), 0) << client.dump();
  }
  EXPECT_EQ(daemon->Log().find("event=session_demoted"), std::string::npos) << daemon->Log();
}

// A daemon whose steps are heavy from `heavy_step_ms` of CPU on, with `setup_allowance_ms`.
std::vector<std::string> HeavyStepArgs(const TempDir& dir, int heavy_step_ms,
                                       double setup_allowance_ms) {
  const auto config = dir.path() / "far.json";
  std::ofstream(config) << "{\"heavy_step_ms\": " << heavy_step_ms
                        << ", \"setup_allowance_ms\": " << setup_allowance_ms << "}";
  return {"--config", config.string()};
}

// Two 180,000-triangle grids crossing along a line (about a thousand contacts): each hierarchy
// takes about 40 ms to build, a step after that about a millisecond.
void AddCrossingGrids(RawSession& session) {
  ASSERT_TRUE(session.writer().AddObject(1, FlatGrid(300), Motion::kStatic, Pose{}).ok());
  Pose upright;  // the grid turned upright into the plane y = 0.5
  upright.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  upright.translation = Eigen::Vector3d(0.25, 0.5, -0.5);
  ASSERT_TRUE(session.writer().AddObject(2, FlatGrid(300), Motion::kRigid, upright).ok());
}

// Runs steps 0 .. steps - 1 of `session` with bvh; false on an error reply.
::testing::AssertionResult RunSteps(RawSession& session, int first, int steps) {
  for (int step = first; step < first + steps; ++step) {
    if (auto sent = session.SendStep(step, SmallRequest(Method::kBvh)); !sent.ok())
      return ::testing::AssertionFailure() << far::ToString(sent.error());
    auto reply = session.WaitStepReply(step, 60s);
    if (!reply) return ::testing::AssertionFailure() << "no reply to step " << step;
    if (reply->status != 0) return ::testing::AssertionFailure() << reply->message;
  }
  return ::testing::AssertionSuccess();
}

// A daemon with heavy_step_ms 10 and the given setup allowance, and one session on the
// crossing grids, whose first step (the two builds) has run.
class SetupAllowanceTest : public DaemonTest {
 protected:
  void OpenLargeScene(double setup_allowance_ms) {
    daemon_ = StartDaemon(HeavyStepArgs(dir_, 10, setup_allowance_ms));
    ASSERT_NE(daemon_, nullptr);
    auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "large-scene");
    ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
    raw_ = std::move(*raw);
    AddCrossingGrids(*raw_);
    ASSERT_TRUE(RunSteps(*raw_, 0, 1));
  }
  bool Demoted() const {
    const std::string tag = "event=session_demoted session=" + std::to_string(raw_->id());
    return daemon_->Log().find(tag) != std::string::npos;
  }

  TempDir dir_;
  DaemonProcess* daemon_ = nullptr;
  std::unique_ptr<RawSession> raw_;
};

// One-off work is no step's steady cost: a session whose first step builds two large
// hierarchies (more than heavy_step_ms of the worker's CPU) and whose later steps are light is
// not demoted. Judged on its whole first step, it was, for good: a 360K-triangle scene whose
// steps take 3.5 ms was then served at 4.5 steps/s beside light sessions, 30 when not demoted.
TEST_F(SetupAllowanceTest, ASessionIsNotDemotedForTheHierarchiesItsFirstStepBuilds) {
  ASSERT_NO_FATAL_FAILURE(OpenLargeScene(1000));
  ASSERT_TRUE(RunSteps(*raw_, 1, 4));
  EXPECT_FALSE(Demoted()) << daemon_->Log();
}

// The same session with no setup allowance is demoted by its first step: the test above sees
// the allowance at work, not a first step too light to matter.
TEST_F(SetupAllowanceTest, WithoutAnAllowanceItsFirstStepMakesItHeavy) {
  ASSERT_NO_FATAL_FAILURE(OpenLargeScene(0));
  EXPECT_TRUE(Demoted()) << daemon_->Log();
  EXPECT_NE(daemon_->Log().find("setup_covered_ms=0.0"), std::string::npos) << daemon_->Log();
}

// The allowance is a budget, not a pass: a client that adds a new large object at every step
// (and removes the last) is demoted once its user's allowance is spent.
TEST_F(SetupAllowanceTest, AClientThatBuildsAtEveryStepIsDemotedOnceItsAllowanceIsSpent) {
  ASSERT_NO_FATAL_FAILURE(OpenLargeScene(60));
  for (int step = 1; step < 12 && !Demoted(); ++step) {
    // A new copy of the static grid in place of the last one: built anew.
    const uint32_t id = static_cast<uint32_t>(step + 2);
    ASSERT_TRUE(raw_->writer().RemoveObject(step == 1 ? 1 : id - 1).ok());
    ASSERT_TRUE(raw_->writer().AddObject(id, FlatGrid(300), Motion::kStatic, Pose{}).ok());
    ASSERT_TRUE(RunSteps(*raw_, step, 1));
  }
  EXPECT_TRUE(WaitUntil([&] { return Demoted(); }, 2s)) << daemon_->Log();
}

}  // namespace
}  // namespace far::integration
