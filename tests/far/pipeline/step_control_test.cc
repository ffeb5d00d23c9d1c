// Pipeline::Step under a StepControl: progress per stage, cancellation, deadline, the report of
// a step that runs long and the cap on the reply's pairs; the brute-force reference refused on
// scenes too large for it.
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "far/base/limits.h"
#include "far/pipeline/pipeline.h"

namespace far {
namespace {

using namespace std::chrono_literals;

// A flat n x n grid (2 n^2 triangles) in the plane z = 0, its corner at (dx, 0, 0).
Mesh Grid(int n, double dx) {
  Mesh mesh;
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) mesh.p_MV.emplace_back(x + dx, y, 0);
  }
  const auto at = [n](int x, int y) { return static_cast<uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      mesh.triangles.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      mesh.triangles.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  }
  return mesh;
}

// Two coplanar grids half a cell apart: hundreds of contacts.
std::unique_ptr<Pipeline> TwoGrids(int n) {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok());
  EXPECT_TRUE((*pipeline)->AddObject(1, Grid(n, 0), Motion::kStatic).ok());
  EXPECT_TRUE((*pipeline)->AddObject(2, Grid(n, 0.5), Motion::kRigid).ok());
  return std::move(*pipeline);
}

StepRequest Request(Method method) {
  StepRequest request;
  request.method = method;
  return request;
}

TEST(StepControlTest, ReportsEveryStageItEntersInOrder) {
  auto pipeline = TwoGrids(6);
  std::vector<Stage> stages;
  StepControl control;
  control.on_stage = [&](Stage stage) { stages.push_back(stage); };
  ASSERT_TRUE(pipeline->Step(Request(Method::kBvh), control).ok());
  EXPECT_EQ(stages, (std::vector<Stage>{Stage::kUpdate, Stage::kObjectCull, Stage::kSweepAndPrune,
                                        Stage::kExact}));
  stages.clear();
  ASSERT_TRUE(pipeline->Step(Request(Method::kAabb), control).ok());
  EXPECT_EQ(stages, (std::vector<Stage>{Stage::kUpdate, Stage::kObjectCull, Stage::kSweepAndPrune,
                                        Stage::kPrimitiveCull, Stage::kExact}));
}

TEST(StepControlTest, ACancelledStepIsAnErrorAndTheNextStepRunsOnTheSameScene) {
  auto pipeline = TwoGrids(6);
  const auto expected = pipeline->Step(Request(Method::kBvh));
  ASSERT_TRUE(expected.ok());
  std::atomic<bool> cancel{false};
  StepControl control;
  control.cancel = &cancel;
  control.on_stage = [&](Stage stage) {
    if (stage == Stage::kSweepAndPrune) cancel = true;
  };
  const auto cancelled = pipeline->Step(Request(Method::kBvh), control);
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(cancelled.error().message.find("cancelled"), std::string::npos);
  EXPECT_NE(cancelled.error().message.find("sweep_and_prune"), std::string::npos);
  const auto again = pipeline->Step(Request(Method::kBvh));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->contacts, expected->contacts);
}

TEST(StepControlTest, AStepPastItsDeadlineIsATimeout) {
  auto pipeline = TwoGrids(6);
  StepControl control;
  control.deadline = StepControl::Clock::now();
  const auto late = pipeline->Step(Request(Method::kAabb), control);
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kTimeout);
}

TEST(StepControlTest, EveryThreadOfAStepThatRunsLongIsToldWhileItRuns) {
  auto pipeline = TwoGrids(40);  // 3,200 x 3,200 triangle pairs for the brute force
  std::mutex mutex;
  std::set<std::thread::id> told;
  int calls = 0;
  StepControl control;
  control.on_slow = [&] {
    std::lock_guard lock(mutex);
    told.insert(std::this_thread::get_id());
    ++calls;
  };
  // Not yet slow: never told.
  control.slow_after = StepControl::Clock::now() + std::chrono::hours(1);
  ASSERT_TRUE(pipeline->Step(Request(Method::kExact), control).ok());
  EXPECT_EQ(calls, 0);
  // Slow from the start: told at the first stage and by each thread of the exact tests.
  control.slow_after = StepControl::Clock::now();
  ASSERT_TRUE(pipeline->Step(Request(Method::kExact), control).ok());
  EXPECT_GT(calls, 1);
  EXPECT_EQ(told.size(), 2u) << "the calling thread and the pool's worker";
}

// What a step marks as setup (StepControl::on_setup_begin/end), seen from the step's thread:
// how many parts, and which stages ran inside one.
struct SetupLog {
  int parts = 0;
  int depth = 0;
  bool balanced = true;
  bool other_thread = false;
  std::vector<std::string> stages_inside;
  std::vector<std::string> stages_outside;
};

StepControl LoggingSetup(SetupLog& log) {
  const std::thread::id caller = std::this_thread::get_id();
  StepControl control;
  control.on_setup_begin = [&log, caller] {
    log.other_thread |= std::this_thread::get_id() != caller;
    if (log.depth++ == 0) ++log.parts;
  };
  control.on_setup_end = [&log, caller] {
    log.other_thread |= std::this_thread::get_id() != caller;
    log.balanced &= --log.depth >= 0;
  };
  control.on_stage = [&log](Stage stage) {
    (log.depth > 0 ? log.stages_inside : log.stages_outside).emplace_back(ToString(stage));
  };
  return control;
}

TEST(StepControlTest, HierarchyBuildsAreSetupAndTheStepsAfterThemHaveNone) {
  for (Method method : {Method::kBvh, Method::kFcl}) {
    SCOPED_TRACE(std::string(ToString(method)));
    auto pipeline = TwoGrids(20);
    SetupLog first;
    ASSERT_TRUE(pipeline->Step(Request(method), LoggingSetup(first)).ok());
    EXPECT_GE(first.parts, 1) << "the two new objects' hierarchies were built";
    EXPECT_TRUE(first.balanced && first.depth == 0 && !first.other_thread);
    EXPECT_TRUE(first.stages_inside.empty()) << "the builds are part of a stage, not a stage";
    // The rigid grid moves: its hierarchy is kept.
    ASSERT_TRUE(pipeline->SetPose(2, Pose{Eigen::Vector3d(0.25, 0, 0)}).ok());
    SetupLog moved;
    ASSERT_TRUE(pipeline->Step(Request(method), LoggingSetup(moved)).ok());
    EXPECT_EQ(moved.parts, 0);
    // A new object: its build is setup again.
    ASSERT_TRUE(pipeline->AddObject(3, Grid(4, 1), Motion::kRigid).ok());
    SetupLog added;
    ASSERT_TRUE(pipeline->Step(Request(method), LoggingSetup(added)).ok());
    EXPECT_GE(added.parts, 1);
    EXPECT_TRUE(added.balanced && added.depth == 0);
  }
}

TEST(StepControlTest, AutoStepsThatCalibrateAreSetupAndTheChosenOnesAreNot) {
  auto pipeline = TwoGrids(10);
  // Without a GPU, auto tries bvh twice (its first run on new objects, then again), then runs
  // it as the one chosen.
  for (int step = 0; step < 4; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    SetupLog log;
    auto result = pipeline->Step(Request(Method::kAuto), LoggingSetup(log));
    ASSERT_TRUE(result.ok());
    EXPECT_TRUE(log.balanced && log.depth == 0 && !log.other_thread);
    const bool calibrating = result->stats.method_reason.starts_with("auto: calibrating");
    EXPECT_EQ(calibrating, step < 2) << result->stats.method_reason;
    if (calibrating) {
      EXPECT_TRUE(log.stages_outside.empty()) << "every stage of a try is setup";
      EXPECT_FALSE(log.stages_inside.empty());
    } else {
      EXPECT_TRUE(log.stages_inside.empty()) << "the chosen configuration's stages are no setup";
      EXPECT_FALSE(log.stages_outside.empty());
    }
  }
}

TEST(StepControlTest, TheAabbPrimitiveCullChecksAsItGoes) {
  // 2 x 80,000 triangles: the AABB method's primitive cull tests 160,000 boxes, and checks
  // (here: reports the slow step) every 65,536 of them, not only as the stage starts.
  auto pipeline = TwoGrids(200);
  Stage stage = Stage::kUpdate;
  int during_primitive_cull = 0;
  StepControl control;
  control.on_stage = [&](Stage name) { stage = name; };
  control.on_slow = [&] { during_primitive_cull += stage == Stage::kPrimitiveCull; };
  control.slow_after = StepControl::Clock::now();
  StepRequest request = Request(Method::kAabb);
  request.output = Output::kPrimitivePcs;
  ASSERT_TRUE(pipeline->Step(request, control).ok());
  EXPECT_EQ(during_primitive_cull, 3) << "once as the stage starts, twice within it";
}

TEST(StepControlTest, AnAnswerOverThePairCapIsRefusedByEveryMethod) {
  auto pipeline = TwoGrids(10);
  for (Method method : {Method::kBvh, Method::kAabb, Method::kFcl, Method::kExact}) {
    SCOPED_TRACE(std::string(ToString(method)));
    const auto full = pipeline->Step(Request(method));
    ASSERT_TRUE(full.ok());
    ASSERT_GT(full->contacts.size(), 50u);
    StepControl control;
    control.max_pairs = 50;
    const auto capped = pipeline->Step(Request(method), control);
    ASSERT_FALSE(capped.ok());
    EXPECT_EQ(capped.error().code, ErrorCode::kLimitExceeded);
    EXPECT_NE(capped.error().message.find("more than 50 contact and distance pairs"),
              std::string::npos)
        << capped.error().message;
  }
}

TEST(StepControlTest, DistancePairsCountAgainstTheCapToo) {
  auto pipeline = TwoGrids(10);
  StepRequest request = Request(Method::kBvh);
  request.distance = 1e6;  // every triangle pair
  request.output = Output::kDistancePairs;
  StepControl control;
  control.max_pairs = 10'000;
  const auto capped = pipeline->Step(request, control);
  ASSERT_FALSE(capped.ok());
  EXPECT_EQ(capped.error().code, ErrorCode::kLimitExceeded);
}

TEST(StepControlTest, TheBruteForceReferenceIsRefusedAboveItsSize) {
  // Two grids of 2 * 128^2 = 32,768 triangles: 2^30 pairs, at the limit; one more row is over.
  PipelineOptions options;
  options.use_gl = false;
  auto pipeline = Pipeline::Create(options);
  ASSERT_TRUE(pipeline.ok());
  ASSERT_TRUE((*pipeline)->AddObject(1, Grid(128, 0), Motion::kStatic).ok());
  Mesh bigger = Grid(128, 1000);
  bigger.p_MV.emplace_back(2000, 0, 0);
  bigger.triangles.push_back({0, 1, static_cast<uint32_t>(bigger.p_MV.size() - 1)});
  ASSERT_TRUE((*pipeline)->AddObject(2, bigger, Motion::kStatic).ok());
  const auto refused = (*pipeline)->Step(Request(Method::kExact));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(refused.error().message.find(std::to_string(kMaxBruteForcePairs)), std::string::npos);
  EXPECT_NE(refused.error().message.find("'bvh'"), std::string::npos);
  EXPECT_TRUE((*pipeline)->Step(Request(Method::kBvh)).ok());
}

// One large grid and a triangle standing across it along the line y = 0.2719 n: a few hundred
// contacts, none on a grid line or vertex.
std::unique_ptr<Pipeline> GridAndBlade(int n) {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok());
  EXPECT_TRUE((*pipeline)->AddObject(1, Grid(n, 0), Motion::kStatic).ok());
  Mesh blade;
  const double y = 0.2719 * n;
  blade.p_MV = {{0.3137 * n, y, -5}, {0.7071 * n, y, -5}, {0.5113 * n, y, 5}};
  blade.triangles = {{0, 1, 2}};
  EXPECT_TRUE((*pipeline)->AddObject(2, blade, Motion::kRigid).ok());
  return std::move(*pipeline);
}

// How late a stopped step may end. Issue 41 asks for 1 s (or 5% of the deadline); the stages
// here check every few milliseconds, so half of that still leaves a wide margin for a loaded
// machine, and fails a stage that does not check (which ran 1.5 s past the deadline here).
constexpr auto kStopBound = std::chrono::milliseconds(500);

// Runs `request` with a deadline `after` from now; returns the error and how far past the
// deadline the step ended.
std::pair<Error, StepControl::Clock::duration> StepPastDeadline(Pipeline& pipeline,
                                                                const StepRequest& request,
                                                                std::chrono::milliseconds after) {
  StepControl control;
  control.deadline = StepControl::Clock::now() + after;
  auto result = pipeline.Step(request, control);
  const auto past = StepControl::Clock::now() - control.deadline;
  EXPECT_FALSE(result.ok()) << "the step ended within its deadline: make the scene larger";
  return {result.ok() ? Error{} : result.error(), past};
}

long long Ms(StepControl::Clock::duration d) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
}

TEST(StepControlTest, TheHierarchyBuildOfTheLargestObjectStopsAtTheDeadline) {
  // 2,000,000 triangles, the most a daemon session may hold: their hierarchy takes seconds to
  // build, and was built whole before the step looked at its deadline again.
  auto pipeline = GridAndBlade(1000);
  // A first step places the vertices in the world (a tenth of a second): the next one's time
  // goes to the hierarchy.
  StepRequest place = Request(Method::kAabb);
  place.output = Output::kObjectPcs;
  ASSERT_TRUE(pipeline->Step(place).ok());
  const auto [error, past] = StepPastDeadline(*pipeline, Request(Method::kBvh), 100ms);
  EXPECT_EQ(error.code, ErrorCode::kTimeout) << error.message;
  EXPECT_NE(error.message.find("during exact"), std::string::npos) << error.message;
  EXPECT_LT(past, kStopBound) << "ended " << Ms(past) << " ms past its deadline";
  // The abandoned build is done again by the next step, which answers as the aabb method does.
  const auto bvh = pipeline->Step(Request(Method::kBvh));
  const auto aabb = pipeline->Step(Request(Method::kAabb));
  ASSERT_TRUE(bvh.ok() && aabb.ok());
  EXPECT_GT(bvh->contacts.size(), 100u);
  EXPECT_EQ(bvh->contacts, aabb->contacts);
}

TEST(StepControlTest, AnFclModelBuildStopsTheStepAtTheDeadlineAndALaterStepUsesIt) {
  // 500,000 triangles: FCL builds their model in seconds, and cannot be interrupted; the step
  // stops waiting for it, and the build goes on for the next step.
  auto pipeline = GridAndBlade(500);
  const auto [error, past] = StepPastDeadline(*pipeline, Request(Method::kFcl), 100ms);
  EXPECT_EQ(error.code, ErrorCode::kTimeout) << error.message;
  EXPECT_LT(past, kStopBound) << "ended " << Ms(past) << " ms past its deadline";
  const auto fcl = pipeline->Step(Request(Method::kFcl));
  const auto bvh = pipeline->Step(Request(Method::kBvh));
  ASSERT_TRUE(fcl.ok() && bvh.ok());
  EXPECT_GT(fcl->contacts.size(), 100u);
  EXPECT_EQ(fcl->contacts, bvh->contacts);
}

}  // namespace
}  // namespace far
