// The long stages stop when their StepControl says so: a cancel flag, a deadline, a cap on the
// pairs they report. A stopped stage returns no pairs at all (never a partial answer).
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "far/pairs/bvh_stage.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/triangle_bvh.h"

namespace far {
namespace {

// A flat n x n grid of unit cells in the plane z = 0 (2 n^2 triangles), shifted by `dx`.
struct Grid {
  std::vector<Eigen::Vector3d> p;
  std::vector<TriangleIndices> triangles;
  TriangleBvh bvh;

  Grid(int n, double dx) {
    for (int y = 0; y <= n; ++y) {
      for (int x = 0; x <= n; ++x) p.emplace_back(x + dx, y, 0);
    }
    const auto at = [n](int x, int y) { return static_cast<uint32_t>(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        triangles.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
        triangles.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
      }
    }
    bvh.Build(p, triangles);
  }
};

// Two coplanar grids half a cell apart: every triangle touches several of the other's.
struct TwoGrids {
  Grid a, b;
  explicit TwoGrids(int n) : a(n, 0), b(n, 0.5) {}
  std::vector<WorldObjectView> Views() const { return {{a.p, a.triangles}, {b.p, b.triangles}}; }
  std::vector<ObjectHierarchy> Hierarchies() const {
    return {{&a.bvh, Eigen::Isometry3d::Identity()}, {&b.bvh, Eigen::Isometry3d::Identity()}};
  }
};

const std::vector<SlotPair> kPair = {{SlotAt(0), SlotAt(1)}};

ExactResult RunExact(const TwoGrids& scene, ThreadPool& pool, const StepControl* control) {
  const auto views = scene.Views();
  ExactQuery query;
  query.objects = views;
  query.object_pairs = kPair;
  query.control = control;
  return RunExactTests(query, pool);
}

ExactResult RunBvh(const TwoGrids& scene, ThreadPool& pool, const StepControl* control) {
  const auto views = scene.Views();
  const auto hierarchies = scene.Hierarchies();
  BvhQuery query;
  query.objects = views;
  query.hierarchies = hierarchies;
  query.object_pairs = kPair;
  query.control = control;
  return RunBvhTests(query, pool).exact;
}

ExactResult RunBrute(const TwoGrids& scene, ThreadPool& pool, const StepControl* control) {
  return BruteForceReference(scene.Views(), std::nullopt, pool, control);
}

using Runner = ExactResult (*)(const TwoGrids&, ThreadPool&, const StepControl*);
const std::vector<std::pair<const char*, Runner>> kStages = {
    {"exact stage", RunExact}, {"hierarchy stage", RunBvh}, {"brute force", RunBrute}};

TEST(StageStopTest, EveryStageStopsAtThePairCapAndReturnsNoPairs) {
  const TwoGrids scene(12);
  ThreadPool pool(2);
  for (const auto& [name, run] : kStages) {
    SCOPED_TRACE(name);
    const ExactResult full = run(scene, pool, nullptr);
    ASSERT_GT(full.contacts.size(), 200u);
    StepControl control;
    control.max_pairs = 100;
    const ExactResult capped = run(scene, pool, &control);
    EXPECT_EQ(capped.stopped, StopReason::kPairLimit);
    EXPECT_TRUE(capped.contacts.empty());
    // A cap the answer fits is no limit: the same answer.
    control.max_pairs = full.contacts.size();
    const ExactResult fits = run(scene, pool, &control);
    EXPECT_EQ(fits.stopped, StopReason::kNone);
    EXPECT_EQ(fits.contacts, full.contacts);
  }
}

TEST(StageStopTest, EveryStageStopsWhenCancelledOrPastItsDeadline) {
  const TwoGrids scene(12);
  ThreadPool pool(2);
  for (const auto& [name, run] : kStages) {
    SCOPED_TRACE(name);
    std::atomic<bool> cancel{true};
    StepControl cancelled;
    cancelled.cancel = &cancel;
    const ExactResult a = run(scene, pool, &cancelled);
    EXPECT_EQ(a.stopped, StopReason::kCancelled);
    EXPECT_TRUE(a.contacts.empty());
    StepControl late;
    late.deadline = StepControl::Clock::now() - std::chrono::milliseconds(1);
    const ExactResult b = run(scene, pool, &late);
    EXPECT_EQ(b.stopped, StopReason::kDeadline);
    EXPECT_TRUE(b.contacts.empty());
  }
}

// A cancel that arrives while the stage runs stops it: the brute force of two 20,000-triangle
// grids (4e8 pairs, seconds of work) is cancelled 20 ms in.
TEST(StageStopTest, ABruteForceRunIsCancelledFromAnotherThreadWhileItRuns) {
  const TwoGrids scene(100);
  ThreadPool pool(2);
  std::atomic<bool> cancel{false};
  StepControl control;
  control.cancel = &cancel;
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    cancel = true;
  });
  const ExactResult result = RunBrute(scene, pool, &control);
  canceller.join();
  EXPECT_EQ(result.stopped, StopReason::kCancelled);
  EXPECT_TRUE(result.contacts.empty());
}

TEST(StageStopTest, BruteForcePairsCountsEveryCrossObjectPair) {
  const std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<TriangleIndices> two(2, {0, 1, 2}), three(3, {0, 1, 2}), five(5, {0, 1, 2});
  const std::vector<WorldObjectView> views = {{p, two}, {p, three}, {p, five}};
  EXPECT_EQ(BruteForcePairs(views), 2u * 3 + 2 * 5 + 3 * 5);
  EXPECT_EQ(BruteForcePairs({}), 0u);
}

}  // namespace
}  // namespace far
