// Deadlines and the GL path between sessions (issue 41): a session's GL views take turns with
// other sessions' views batch by batch, so a light GL session beside a heavy one waits little,
// and a step that waited in its queue until just before its deadline, then stopped there, is not
// remembered as too heavy.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include "test_scenes.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Two crossing stacks of `layers` large triangles (tests/far/pipeline/gl_deadline_test.cc): every
// GPU view draws every piece over half its viewport, seconds per view at 2048^2 on llvmpipe.
void UploadFillHeavyScene(RawSession& session, int layers = 300) {
  Pose turned;
  turned.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  turned.translation = Eigen::Vector3d(0, 0, 0.5);
  const Mesh stack = testing::StackedTriangles(layers, 0.3, -1e-3);
  ASSERT_TRUE(session.writer().AddObject(1, stack, Motion::kStatic, Pose{}).ok());
  ASSERT_TRUE(session.writer().AddObject(2, stack, Motion::kStatic, turned).ok());
}

StepRequest Gl(QueryMechanism mechanism, int resolution) {
  StepRequest request = SmallRequest(Method::kFar);
  request.mechanism = mechanism;
  request.resolution = resolution;
  return request;
}

bool Refused(const far_lcm::step_reply_t& reply) {
  return reply.message.find("refused before it ran") != std::string::npos;
}

class DeadlineTest : public DaemonTest {
 protected:
  // A heavy GL session drawing with `mechanism`; a light GL and a light CPU session beside it.
  void LightSessionsBesideAHeavyGlSession(QueryMechanism mechanism);
};

TEST_F(DeadlineTest, AStepThatWaitedInItsQueueUntilNearItsDeadlineIsNotBlamedForIt) {
  // A 2 s step deadline: a step is blamed for it when it ran for 1 s of it on its own.
  ASSERT_NE(StartDaemon({"--step-deadline-ms", "2000"}), nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "queued");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  UploadFillHeavyScene(**raw);
  // Step 0 runs into the deadline (its views would take many seconds); step 1, sent 400 ms
  // after it, waits in the queue until step 0 stops, then runs for what is left of its own
  // deadline and stops there too.
  const StepRequest heavy = Gl(QueryMechanism::kOcclusionQuery, 2048);
  const StepRequest queued = Gl(QueryMechanism::kIdBuffer, 1024);
  ASSERT_TRUE((*raw)->SendStep(0, heavy).ok());
  std::this_thread::sleep_for(400ms);
  ASSERT_TRUE((*raw)->SendStep(1, queued).ok());
  const auto first = (*raw)->WaitStepReply(0, 20s);
  const auto second = (*raw)->WaitStepReply(1, 20s);
  ASSERT_TRUE(first.has_value() && second.has_value());
  ASSERT_EQ(first->status, protocol::ToWireStatus(ErrorCode::kTimeout)) << first->message;
  ASSERT_EQ(second->status, protocol::ToWireStatus(ErrorCode::kTimeout)) << second->message;
  ASSERT_NE(second->message.find("stopped at its deadline"), std::string::npos)
      << "step 1 must have run, briefly: " << second->message;

  // The same request again: it runs (it is not refused for step 1's deadline), and as it runs
  // into the deadline on its own time, the next one is refused.
  ASSERT_TRUE((*raw)->SendStep(2, queued).ok());
  const auto third = (*raw)->WaitStepReply(2, 20s);
  ASSERT_TRUE(third.has_value());
  EXPECT_FALSE(Refused(*third)) << third->message;
  EXPECT_NE(third->message.find("stopped at its deadline"), std::string::npos) << third->message;
  ASSERT_TRUE((*raw)->SendStep(3, queued).ok());
  const auto fourth = (*raw)->WaitStepReply(3, 20s);
  ASSERT_TRUE(fourth.has_value());
  EXPECT_EQ(fourth->status, protocol::ToWireStatus(ErrorCode::kLimitExceeded)) << fourth->message;
  EXPECT_TRUE(Refused(*fourth)) << fourth->message;
}

// Steps `client` with `request` for `seconds`: each step's round trip, ms.
std::vector<double> StepFor(client::Client& client, const StepRequest& request, double seconds) {
  std::vector<double> ms;
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    const auto start = Clock::now();
    auto result = client.Step(request);
    EXPECT_TRUE(result.ok()) << far::ToString(result.error());
    if (!result.ok()) break;
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  return ms;
}

// A light client's whole life: it connects, uploads the healthy scene and steps `request` for
// `seconds`; each step's round trip, ms (the first makes its GL context and renderer).
std::vector<double> LightClientSteps(const std::string& name, const StepRequest& request,
                                     double seconds) {
  auto client = client::Client::Connect(TestClientOptions(name));
  EXPECT_TRUE(client.ok()) << far::ToString(client.error());
  if (!client.ok()) return {};
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  EXPECT_TRUE((*client)->LoadScene(scene).ok());
  return StepFor(**client, request, seconds);
}

double Worst(const std::vector<double>& ms) {
  return ms.empty() ? INFINITY : *std::max_element(ms.begin(), ms.end());
}

void DeadlineTest::LightSessionsBesideAHeavyGlSession(QueryMechanism mechanism) {
  // (--status-after-ms 0: the test waits for the heavy step's primitive_cull status)
  ASSERT_NE(StartDaemon({"--step-deadline-ms", "6000", "--status-after-ms", "0"}), nullptr);
  auto heavy = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "heavy");
  ASSERT_TRUE(heavy.ok()) << far::ToString(heavy.error());
  // Stacks of 600 layers: with 300, the occlusion queries' views finished inside the 6 s
  // deadline on a faster CI machine (1.5 and 2.0 s after the light clients were done, timed).
  UploadFillHeavyScene(**heavy, 600);
  // The heavy step's views run from its primitive stage on (its renderer made, its pieces built)
  // until its deadline: seconds of GL work per view.
  ASSERT_TRUE((*heavy)->SendStep(0, Gl(mechanism, 2048)).ok());
  ASSERT_TRUE(
      (*heavy)
          ->WaitReply(
              [](const ReplyMessage& m) { return m.status && m.status->stage == "primitive_cull"; },
              20s)
          .has_value());
  // A light GL client (256^2) and a light CPU client (bvh; its session makes a GL context too)
  // open their sessions and step meanwhile.
  const std::vector<double> gl =
      LightClientSteps("light-gl", Gl(QueryMechanism::kIdBuffer, 256), 2.5);
  const std::vector<double> cpu = LightClientSteps("light-cpu", SmallRequest(Method::kBvh), 1.0);
  // The light clients must have stepped beside the heavy step: it has not answered yet (what
  // arrived in the last 50 ms is read first), and when it does it stops at its deadline.
  EXPECT_FALSE((*heavy)->WaitStepReply(0, 50ms).has_value())
      << "the heavy step must still have been drawing when the light clients were done";
  const auto reply = (*heavy)->WaitStepReply(0, 20s);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, protocol::ToWireStatus(ErrorCode::kTimeout))
      << "the heavy step should have run into its deadline: " << reply->message;
  // Every light GL step, in order: one slow step among fast ones is one long batch of the heavy
  // view's, not the machine's load (CI once failed on one such step).
  std::string gl_ms;
  for (double ms : gl) gl_ms += " " + std::to_string(static_cast<int>(ms));
  std::printf(
      "light GL client: %zu steps, worst %.0f ms, each:%s; light CPU client: %zu steps, "
      "worst %.0f ms\n",
      gl.size(), Worst(gl), gl_ms.c_str(), cpu.size(), Worst(cpu));
  // Issue 41 asks for 1 s at most on 2 cores; a light step waits for a batch of the heavy
  // session's draws at each of its views (a few to tens of milliseconds each).
  EXPECT_LT(Worst(gl), 1000) << "the light GL client's slowest step, ms";
  EXPECT_LT(Worst(cpu), 1000) << "the light CPU client's slowest step, ms";
  EXPECT_GE(gl.size(), 5u);
}

TEST_F(DeadlineTest, LightSessionsBesideAHeavyGlSessionWaitForItLittle) {
  LightSessionsBesideAHeavyGlSession(QueryMechanism::kIdBuffer);
}

// The occlusion queries are drawn one primitive at a time, outside the batches: the pauses
// between them are judged by what they may cost (DrawPacer::NoteDrawn). Judged every 128
// queries by the CPU time spent issuing them, the light GL client's worst step was 353-543 ms.
TEST_F(DeadlineTest, LightSessionsBesideAHeavyOcclusionQuerySessionWaitForItLittle) {
  LightSessionsBesideAHeavyGlSession(QueryMechanism::kOcclusionQuery);
}

}  // namespace
}  // namespace far::integration
