// Many threads and many sessions in one process (docs/client.md, "Threads"): eight threads, each
// stepping its own Client (its own session and ~1K-triangle scene, moved every step), get
// every answer exact, checked against the brute-force reference of the same scene; one Client
// shared by several threads that update and step it at once answers every step right, each
// step once; and a Close on one thread ends the steps of the others at once, not at their
// timeout. Small and quick (a few seconds; CI runs it under ThreadSanitizer too:
// deploy/run-sanitizers.sh).

#include <atomic>
#include <chrono>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "test_scenes.h"
#include <gtest/gtest.h>

#include "far/base/thread_pool.h"
#include "far/client/client.h"
#include "far/scenes/scenes.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kThreads = 8;
constexpr int kSteps = 12;
constexpr int kFrames = 4;  // the poses each thread cycles through: kFrames references each

// Thread `t`'s scene: far-client load's soup (24 rigid clusters of 40 triangles, 960 in all),
// its poses as the client sends them (normalized), so that the reference sees the same bits.
std::vector<SceneObject> ThreadScene(int t) {
  std::vector<SceneObject> objects =
      scenes::RandomSoup(static_cast<uint64_t>(100 + t), 24, 40, 3.0, 0.4);
  for (SceneObject& object : objects) object.X_WO = *CheckAndNormalizePose(object.X_WO);
  return objects;
}

// Frame `k` of a scene: every object moved along x by its own small amount (k = 0: as made).
std::vector<SceneObject> Frame(std::vector<SceneObject> objects, int k) {
  for (SceneObject& object : objects) {
    object.X_WO.translation.x() += 0.03 * k * static_cast<double>(object.id % 5);
  }
  return objects;
}

StepRequest Contacts(Method method) {
  StepRequest request;
  request.method = method;
  request.output = Output::kContacts;
  return request;
}

StepRequest BvhContacts() { return Contacts(Method::kBvh); }

class ManyThreadsTest : public DaemonTest {
 protected:
  // Eight threads, each stepping its own session with `method`, every answer the reference's.
  void EightThreadsGetExactAnswers(Method method);
};

TEST_F(ManyThreadsTest, EightThreadsEachSteppingTheirOwnSessionGetExactAnswers) {
  EightThreadsGetExactAnswers(Method::kBvh);
}

// The gpu method's steps of the eight sessions go to the daemon's batcher (--gpu-batch, on by
// default; several in a batch when they wait together): each session gets its own answer, exact.
TEST_F(ManyThreadsTest, EightThreadsSteppingTheGpuMethodThroughTheBatcherGetExactAnswers) {
  EightThreadsGetExactAnswers(Method::kGpu);
}

void ManyThreadsTest::EightThreadsGetExactAnswers(Method method) {
  ASSERT_NE(StartDaemon(), nullptr);
  // The references, before any thread starts: [thread][frame].
  std::vector<std::vector<SceneObject>> scenes;
  std::vector<std::vector<std::vector<ContactPair>>> expected(kThreads);
  {
    ThreadPool pool(2);
    for (int t = 0; t < kThreads; ++t) {
      scenes.push_back(ThreadScene(t));
      for (int k = 0; k < kFrames; ++k) {
        expected[t].push_back(
            testing::ReferenceAnswer(Frame(scenes[t], k), std::nullopt, pool).contacts);
      }
    }
  }
  int with_contacts = 0;
  for (const auto& frames : expected) with_contacts += frames[0].empty() ? 0 : 1;
  ASSERT_GE(with_contacts, kThreads / 2) << "the scenes should have contacts to check";

  struct Outcome {
    int steps = 0, wrong = 0;
    std::string first_problem;
  };
  std::vector<Outcome> outcomes(kThreads);
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      Outcome& mine = outcomes[t];
      auto problem = [&](const std::string& what) {
        if (mine.wrong++ == 0) mine.first_problem = what;
      };
      // Connect on the thread itself: sessions open concurrently too.
      auto client = client::Client::Connect(TestClientOptions("thread-" + std::to_string(t), 30s));
      ++ready;
      if (!client) return problem("connect: " + far::ToString(client.error()));
      for (const SceneObject& object : scenes[t]) {
        if (auto ok = (*client)->AddObject(object.id, object.mesh, object.motion, object.X_WO);
            !ok) {
          return problem("add_object: " + far::ToString(ok.error()));
        }
      }
      while (!go) std::this_thread::sleep_for(1ms);
      for (int s = 0; s < kSteps; ++s) {
        const int k = s % kFrames;
        if (s > 0) {
          for (const SceneObject& object : Frame(scenes[t], k)) {
            if (auto ok = (*client)->SetPose(object.id, object.X_WO); !ok) {
              return problem("set_pose: " + far::ToString(ok.error()));
            }
          }
        }
        auto result = (*client)->Step(Contacts(method));
        if (!result)
          return problem("step " + std::to_string(s) + ": " + far::ToString(result.error()));
        ++mine.steps;
        if (result->stats.method != ToString(method)) {
          problem("step " + std::to_string(s) + " ran " + result->stats.method);
        } else if (result->contacts != expected[t][k]) {
          problem("step " + std::to_string(s) + " (frame " + std::to_string(k) +
                  "): " + std::to_string(result->contacts.size()) + " contacts " +
                  ToString(result->contacts, 5) + ", the reference " +
                  std::to_string(expected[t][k].size()) + " " + ToString(expected[t][k], 5));
        }
      }
    });
  }
  while (ready < kThreads) std::this_thread::sleep_for(1ms);
  go = true;
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_EQ(outcomes[t].steps, kSteps) << "thread " << t << ": " << outcomes[t].first_problem;
    EXPECT_EQ(outcomes[t].wrong, 0) << "thread " << t << ": " << outcomes[t].first_problem;
  }
}

TEST_F(ManyThreadsTest, OneClientUpdatedAndSteppedByFourThreadsAtOnceAnswersEveryStep) {
  ASSERT_NE(StartDaemon(), nullptr);
  const std::vector<SceneObject> scene = ThreadScene(0);
  std::vector<ContactPair> expected;
  {
    ThreadPool pool(2);
    expected = testing::ReferenceAnswer(scene, std::nullopt, pool).contacts;
  }
  ASSERT_FALSE(expected.empty());
  auto client = client::Client::Connect(TestClientOptions("shared", 30s));
  ASSERT_TRUE(client) << far::ToString(client.error());
  client::Client& shared = **client;
  Scene loaded;
  loaded.objects = scene;
  ASSERT_TRUE(shared.LoadScene(loaded).ok());
  // Every thread writes the objects of its own quarter (the same poses again: the scene stays
  // the reference's) and steps, synchronously or not: the ring sees whole records only, every
  // step is sent once and answered with its own reply.
  constexpr int kSharers = 4;
  std::atomic<int> wrong{0}, answered{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kSharers; ++t) {
    threads.emplace_back([&, t] {
      for (int s = 0; s < 6; ++s) {
        for (size_t i = t; i < scene.size(); i += kSharers) {
          if (!shared.SetPose(scene[i].id, scene[i].X_WO).ok()) ++wrong;
        }
        auto result =
            s % 2 == 0 ? shared.Step(BvhContacts()) : shared.StepAsync(BvhContacts()).get();
        if (!result) {
          ADD_FAILURE() << "thread " << t << " step " << s << ": " << far::ToString(result.error());
          ++wrong;
          continue;
        }
        ++answered;
        if (result->contacts != expected) ++wrong;
      }
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(answered.load(), kSharers * 6);
  EXPECT_EQ(wrong.load(), 0);
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status) << far::ToString(status.error());
  ASSERT_EQ(status->sessions.size(), 1u);
  EXPECT_EQ(status->sessions[0].steps, kSharers * 6) << "each step runs once";
}

TEST_F(ManyThreadsTest, ACloseOnOneThreadEndsTheStepsOfTheOthersAtOnce) {
  ASSERT_NE(StartDaemon(), nullptr);
  const std::vector<SceneObject> scene = ThreadScene(1);
  // A long timeout: a step left waiting by the close would show as a test that takes it.
  auto client = client::Client::Connect(TestClientOptions("closed", 60s));
  ASSERT_TRUE(client) << far::ToString(client.error());
  client::Client& shared = **client;
  for (const SceneObject& object : scene) {
    ASSERT_TRUE(shared.AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
  }
  std::atomic<int> stepping{0};
  std::vector<std::thread> threads;
  std::vector<std::optional<Error>> ended(3);
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      ++stepping;
      for (;;) {
        auto result = shared.Step(BvhContacts());
        if (!result) {
          ended[t] = result.error();
          return;
        }
      }
    });
  }
  while (stepping < 3) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(100ms);
  const auto closed_at = Clock::now();
  ASSERT_TRUE(shared.Close().ok());
  for (auto& thread : threads) thread.join();
  EXPECT_LT(Clock::now() - closed_at, 5s) << "a step waited for a reply after the close";
  for (int t = 0; t < 3; ++t) {
    ASSERT_TRUE(ended[t].has_value());
    EXPECT_EQ(ended[t]->code, ErrorCode::kUnavailable) << far::ToString(*ended[t]);
  }
  // Every call after the close fails the same way.
  EXPECT_EQ(shared.SetPose(scene[0].id, scene[0].X_WO).error().code, ErrorCode::kUnavailable);
  EXPECT_EQ(shared.Step(BvhContacts()).error().code, ErrorCode::kUnavailable);
}

}  // namespace
}  // namespace far::integration
