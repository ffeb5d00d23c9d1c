// Deadlines on the GL path (label gpu; llvmpipe in CI): a view that would run for seconds stops
// within a batch of its step's deadline, and so does the CPU setup of a large scene's GPU step
// (its GPU geometry, hierarchies and pieces); a step stopped half-way leaves the pipeline
// answering right; views drawn in many small batches give the same PCS as views drawn whole;
// a view pauses between its batches only when something needs the pause, and no batch of a
// heavy view runs long between two pauses.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "test_scenes.h"
#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using testing::RandomSoup;
using testing::StackedTriangles;

// The bound a stopped step must keep: issue 41's "within 1 s (or 5%) of its deadline".
constexpr auto kStopBound = 1000ms;

std::unique_ptr<Pipeline> MakePipeline(double gl_batch_ms = 8) {
  PipelineOptions options;
  options.gl_batch_ms = gl_batch_ms;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok()) << ToString(pipeline.error());
  return pipeline.ok() ? std::move(*pipeline) : nullptr;
}

void Load(Pipeline& pipeline, const std::vector<SceneObject>& objects) {
  for (const SceneObject& object : objects) {
    ASSERT_TRUE(pipeline.AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
  }
}

// A step under a deadline `after` from now: its result, and how long past the deadline it ended.
struct Timed {
  Result<StepResult> result;
  Clock::duration past_deadline;
};
Timed StepWithDeadline(Pipeline& pipeline, const StepRequest& request, Clock::duration after) {
  StepControl control;
  control.deadline = Clock::now() + after;
  auto result = pipeline.Step(request, control);
  return {std::move(result), Clock::now() - control.deadline};
}

std::string Ms(Clock::duration d) {
  return std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(d).count()) + " ms";
}

StepRequest Far(QueryMechanism mechanism, int resolution) {
  StepRequest request;
  request.method = Method::kFar;
  request.mechanism = mechanism;
  request.resolution = resolution;
  return request;
}

// Two stacks of 300 large triangles that cross each other: one of horizontal layers (z from 0.3
// down to 0), one of vertical ones (x from 0.3 down to 0, the same stack turned about y). Every
// triangle of one meets every triangle of the other, so nothing is culled, and each stack fills
// half the viewport 300 times over in the view across its layers, drawn back to front: seconds
// per view at 2048^2 on llvmpipe, with little setup.
std::vector<SceneObject> FillHeavyScene() {
  std::vector<SceneObject> objects(2);
  objects[0].id = 1;
  objects[0].mesh = StackedTriangles(300, 0.3, -1e-3);
  objects[1].id = 2;
  objects[1].mesh = StackedTriangles(300, 0.3, -1e-3);
  objects[1].X_WO.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  objects[1].X_WO.translation = Eigen::Vector3d(0, 0, 0.5);
  return objects;
}

std::string MechanismName(const ::testing::TestParamInfo<QueryMechanism>& info) {
  return info.param == QueryMechanism::kIdBuffer ? "IdBuffer" : "OcclusionQuery";
}

class GlDeadlineTest : public ::testing::TestWithParam<QueryMechanism> {};

// A pipeline whose renderer for `request` has done its one-off setup (shaders, framebuffers) on
// a small scene, now removed: a step's time is then its views'.
std::unique_ptr<Pipeline> WarmedPipeline(const StepRequest& request) {
  auto pipeline = MakePipeline();
  if (pipeline == nullptr) return nullptr;
  const auto warm_up = RandomSoup(1, 3, 4, 2.0, 0.6);
  Load(*pipeline, warm_up);
  const auto warmed = pipeline->Step(request);
  EXPECT_TRUE(warmed.ok()) << ToString(warmed.error());
  for (const SceneObject& object : warm_up) EXPECT_TRUE(pipeline->RemoveObject(object.id).ok());
  return warmed.ok() ? std::move(pipeline) : nullptr;
}

TEST_P(GlDeadlineTest, AViewThatWouldRunForSecondsStopsAtItsDeadline) {
  const StepRequest request = Far(GetParam(), 2048);
  auto pipeline = WarmedPipeline(request);
  ASSERT_NE(pipeline, nullptr);
  Load(*pipeline, FillHeavyScene());
  const Timed stopped = StepWithDeadline(*pipeline, request, 300ms);
  // (The whole step takes 12 s with occlusion queries, 46 s with the ID buffer, on two loaded
  // cores: without pauses between batches it stopped only there, in the exact stage.)
  ASSERT_FALSE(stopped.result.ok()) << "the views ended within 300 ms: make the scene heavier";
  EXPECT_EQ(stopped.result.error().code, ErrorCode::kTimeout);
  const std::string& message = stopped.result.error().message;
  EXPECT_TRUE(message.find("during object_cull") != std::string::npos ||
              message.find("during primitive_cull") != std::string::npos)
      << message;
  EXPECT_LT(stopped.past_deadline, kStopBound)
      << "stopped " << Ms(stopped.past_deadline) << " past its deadline";

  // The pipeline answers right after a view stopped half-way.
  for (uint32_t id : {1u, 2u}) ASSERT_TRUE(pipeline->RemoveObject(id).ok());
  const auto soup = RandomSoup(7, 5, 12, 2.0, 0.6);
  Load(*pipeline, soup);
  ThreadPool pool(2);
  const auto reference = testing::ReferenceAnswer(soup, std::nullopt, pool);
  const auto after = pipeline->Step(request);
  ASSERT_TRUE(after.ok()) << ToString(after.error());
  EXPECT_EQ(after->contacts, reference.contacts);
}

INSTANTIATE_TEST_SUITE_P(BothMechanisms, GlDeadlineTest,
                         ::testing::Values(QueryMechanism::kIdBuffer,
                                           QueryMechanism::kOcclusionQuery),
                         MechanismName);

TEST(GlSetupDeadlineTest, TheCpuSetupOfALargeGpuStepStopsAtItsDeadline) {
  // One object of 720,000 triangles and a small one on it: the GPU step's first work is the big
  // one's GPU geometry, hierarchy and pieces (seconds on two cores), before any view.
  auto pipeline = MakePipeline();
  ASSERT_NE(pipeline, nullptr);
  std::vector<SceneObject> objects(2);
  objects[0].id = 1;
  objects[0].mesh = [] {
    Mesh grid;
    constexpr int n = 600;
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) grid.p_MV.emplace_back(double(i) / n, double(j) / n, 0.0);
    }
    const auto at = [](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        grid.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        grid.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
    return grid;
  }();
  objects[1].id = 2;
  objects[1].mesh.p_MV = {{0.3, 0.3, -0.5}, {0.7, 0.3, -0.5}, {0.5, 0.3, 0.5}};  // across it
  objects[1].mesh.triangles = {{0, 1, 2}};
  Load(*pipeline, objects);
  const StepRequest request = Far(QueryMechanism::kIdBuffer, 256);
  const Timed stopped = StepWithDeadline(*pipeline, request, 100ms);
  ASSERT_FALSE(stopped.result.ok()) << "the setup ended within 100 ms: make the scene larger";
  EXPECT_EQ(stopped.result.error().code, ErrorCode::kTimeout) << stopped.result.error().message;
  EXPECT_LT(stopped.past_deadline, kStopBound)
      << "stopped " << Ms(stopped.past_deadline) << " past its deadline";
  // What was abandoned is done again: the same contacts as the CPU hierarchy method.
  const auto gpu = pipeline->Step(request);
  ASSERT_TRUE(gpu.ok()) << ToString(gpu.error());
  StepRequest bvh;
  bvh.method = Method::kBvh;
  const auto cpu = pipeline->Step(bvh);
  ASSERT_TRUE(cpu.ok()) << ToString(cpu.error());
  EXPECT_FALSE(cpu->contacts.empty());
  EXPECT_EQ(gpu->contacts, cpu->contacts);
}

TEST(GlBatchTest, ViewsDrawnInSmallBatchesGiveTheSamePcs) {
  // gl_batch_ms 0: every piece a batch of its own, with a pause (a check of the step) after each.
  auto whole = MakePipeline();
  auto batched = MakePipeline(0);
  ASSERT_NE(whole, nullptr);
  ASSERT_NE(batched, nullptr);
  for (uint64_t seed = 300; seed < 312; ++seed) {
    const auto soup =
        RandomSoup(seed, 3 + static_cast<int>(seed % 4), 24 + static_cast<int>(seed % 7), 2.0, 0.6);
    std::vector<uint32_t> ids;
    for (const SceneObject& object : soup) ids.push_back(object.id);
    Load(*whole, soup);
    Load(*batched, soup);
    for (Method method : {Method::kFar, Method::kFarExactOffset, Method::kCullide}) {
      for (QueryMechanism mechanism :
           {QueryMechanism::kIdBuffer, QueryMechanism::kOcclusionQuery}) {
        StepRequest request = Far(mechanism, seed % 2 == 0 ? 256 : 1024);
        request.method = method;
        request.output = Output::kPrimitivePcs;
        // Every check of the step calls on_slow: the stages' own, and one per pause.
        // (on_slow runs on whichever thread checks: the pool's too)
        std::atomic<int> checks[2] = {0, 0};
        StepControl counting[2];
        for (int i : {0, 1}) {
          counting[i].slow_after = Clock::now();
          counting[i].on_slow = [&checks, i] { checks[i].fetch_add(1, std::memory_order_relaxed); };
        }
        const auto a = whole->Step(request, counting[0]);
        const auto b = batched->Step(request, counting[1]);
        ASSERT_TRUE(a.ok() && b.ok());
        const std::string what = "seed " + std::to_string(seed) + " " +
                                 std::string(ToString(method)) + " " +
                                 std::string(ToString(mechanism));
        EXPECT_EQ(a->pcs_objects, b->pcs_objects) << what;
        EXPECT_EQ(a->pcs_primitives, b->pcs_primitives) << what;
        EXPECT_GT(checks[1].load(), checks[0].load() + 20)
            << what << ": the views checked the step " << checks[1].load() << " times in batches, "
            << checks[0].load() << " times whole";
      }
    }
    for (uint32_t id : ids) {
      ASSERT_TRUE(whole->RemoveObject(id).ok());
      ASSERT_TRUE(batched->RemoveObject(id).ok());
    }
  }
}

// A pause finishes the GL work (glFinish): a fifth of a long view's time on llvmpipe. In
// process, a step that cannot stop, with no other thread waiting for the GL lock, makes none; a
// step with a deadline (even an hour away) pauses as before. Both give the same PCS.
TEST(GlBatchTest, AViewPausesOnlyWhenTheStepCanStopOrAnotherThreadWaits) {
  auto pipeline = MakePipeline();
  ASSERT_NE(pipeline, nullptr);
  Load(*pipeline, RandomSoup(77, 6, 400, 2.0, 0.9));
  StepRequest request = Far(QueryMechanism::kIdBuffer, 2048);
  request.output = Output::kPrimitivePcs;
  for (QueryMechanism mechanism : {QueryMechanism::kIdBuffer, QueryMechanism::kOcclusionQuery}) {
    request.mechanism = mechanism;
    const auto free_running = pipeline->Step(request);
    const Timed under_deadline = StepWithDeadline(*pipeline, request, 1h);
    ASSERT_TRUE(free_running.ok()) << ToString(free_running.error());
    ASSERT_TRUE(under_deadline.result.ok()) << ToString(under_deadline.result.error());
    const std::string what(ToString(mechanism));
    EXPECT_EQ(free_running->stats.gl_pauses, 0) << what;
    EXPECT_GT(under_deadline.result->stats.gl_pauses, 0) << what << ": the views should be long";
    EXPECT_EQ(free_running->pcs_primitives, under_deadline.result->pcs_primitives) << what;
  }
}

// A view hands the GL lock over at each pause, so the longest stretch between two pauses is
// what a light session beside a heavy one waits for. The crossing stacks' pieces cost 60x more
// face-on than edge-on, and a view draws one stack edge-on, then the other face-on: a batch
// sized on the edge-on pieces' cost ran 0.39 s here (0.4-0.9 s in a daemon, 2 cores). Bounded
// by the pieces' footprints at the measured cost per fragment, the longest ran 54-100 ms. The
// occlusion queries, judged by their CPU time every 128 queries, ran 272-427 ms; judged by
// what each may cost, 24-54 ms.
class GlPauseTest : public ::testing::TestWithParam<QueryMechanism> {};

TEST_P(GlPauseTest, NoBatchOfAHeavyViewRunsLongBetweenPauses) {
  const StepRequest request = Far(GetParam(), 2048);
  auto pipeline = WarmedPipeline(request);
  ASSERT_NE(pipeline, nullptr);
  // The turned stack first: its pieces are seen edge-on in the first view, the other's face-on.
  std::vector<SceneObject> heavy = FillHeavyScene();
  std::swap(heavy[0], heavy[1]);
  Load(*pipeline, heavy);
  // Every check calls on_slow: the stages' own and one per pause.
  // The checks of the step's own thread, which draws the views (the pool's threads check too,
  // concurrently, in the CPU stages: they are not recorded).
  std::vector<Clock::time_point> checks;
  const std::thread::id step_thread = std::this_thread::get_id();
  StepControl control;
  control.slow_after = Clock::now();
  control.deadline = Clock::now() + 4s;
  control.on_slow = [&checks, step_thread] {
    if (std::this_thread::get_id() == step_thread) checks.push_back(Clock::now());
  };
  checks.push_back(Clock::now());
  const auto stopped = pipeline->Step(request, control);
  checks.push_back(Clock::now());
  ASSERT_FALSE(stopped.ok()) << "the views ended within 4 s: make the scene heavier";
  Clock::duration longest{};
  for (size_t i = 1; i < checks.size(); ++i) longest = std::max(longest, checks[i] - checks[i - 1]);
  std::printf("%zu checks, longest gap %s\n", checks.size(), Ms(longest).c_str());
  EXPECT_LT(longest, 200ms) << "the longest stretch between two checks";
}

INSTANTIATE_TEST_SUITE_P(BothMechanisms, GlPauseTest,
                         ::testing::Values(QueryMechanism::kIdBuffer,
                                           QueryMechanism::kOcclusionQuery),
                         MechanismName);

}  // namespace
}  // namespace far
