// How auto chooses, with controlled costs: calibration order, GPU candidates gated by their
// predicted cost, the fastest measured kept, re-calibration when the scene changes or the
// chosen configuration drifts.
#include "far/pipeline/internal/auto_selector.h"

#include <algorithm>
#include <functional>
#include <map>
#include <string>

#include <gtest/gtest.h>

namespace far::internal {
namespace {

// Runs `steps` choices, each "measured" at the time `cost` gives for the chosen candidate.
std::vector<std::string> Steps(AutoSelector& selector, const SceneSize& scene,
                               const std::map<std::string, double>& cost, int steps,
                               std::string* last_reason = nullptr) {
  std::vector<std::string> chosen;
  for (int i = 0; i < steps; ++i) {
    std::string reason;
    const Candidate c = selector.Choose(scene, &reason);
    chosen.push_back(c.Name());
    selector.Record(c, cost.count(c.Name()) ? cost.at(c.Name()) : 1e9);
    if (last_reason != nullptr) *last_reason = reason;
  }
  return chosen;
}

TEST(AutoSelectorTest, WithoutAGpuItIsAlwaysBvh) {
  int probes = 0;
  AutoSelector selector(false, [&] {
    ++probes;
    return std::optional<GpuCost>();
  });
  std::string reason;
  const auto chosen = Steps(selector, {10, 1000}, {{"bvh", 2.0}}, 5, &reason);
  for (const std::string& name : chosen) EXPECT_EQ(name, "bvh");
  EXPECT_EQ(probes, 0);
  EXPECT_NE(reason.find("bvh is the fastest measured"), std::string::npos) << reason;
}

TEST(AutoSelectorTest, ASlowGpuIsNeverTriedOnALargeScene) {
  // A software rasterizer: 5 ms per step plus 30 us per triangle; bvh takes 5 ms.
  AutoSelector selector(true, [] { return std::optional<GpuCost>(GpuCost{5.0, 0.03}); });
  std::string reason;
  const auto chosen = Steps(selector, {150, 40000}, {{"bvh", 5.0}}, 6, &reason);
  for (const std::string& name : chosen) EXPECT_EQ(name, "bvh");
  // Every GPU configuration has the probe's prediction: named once, together.
  EXPECT_NE(reason.find("; not tried (predicted over 3x the best): far/id-buffer/256, "
                        "far/occlusion-query/256, far/id-buffer/1024, far/occlusion-query/1024, "
                        "far-exact-offset/id-buffer/256 1205 ms"),
            std::string::npos)
      << reason;
}

TEST(AutoSelectorTest, AFastGpuIsTriedAndTheFastestMeasuredKept) {
  AutoSelector selector(true, [] { return std::optional<GpuCost>(GpuCost{1.0, 0.0001}); });
  const std::map<std::string, double> cost = {{"bvh", 20.0},
                                              {"far/id-buffer/256", 4.0},
                                              {"far/occlusion-query/256", 6.0},
                                              {"far/id-buffer/1024", 3.0},
                                              {"far/occlusion-query/1024", 8.0},
                                              {"far-exact-offset/id-buffer/256", 5.0}};
  std::string reason;
  const auto chosen = Steps(selector, {10, 100000}, cost, 16, &reason);
  // bvh first, then every GPU candidate, each twice (their first runs on these objects), then
  // the fastest.
  EXPECT_EQ(chosen[0], "bvh");
  EXPECT_EQ(chosen[1], "bvh");
  EXPECT_EQ(chosen[2], "far/id-buffer/256");
  EXPECT_EQ(chosen[3], "far/id-buffer/256");
  for (size_t i = 12; i < chosen.size(); ++i) EXPECT_EQ(chosen[i], "far/id-buffer/1024");
  EXPECT_NE(reason.find("far/id-buffer/1024 is the fastest measured (3.00 ms)"), std::string::npos)
      << reason;
}

TEST(AutoSelectorTest, OneSlowGpuStepRulesOutTheOtherGpuConfigurations) {
  // The probe was optimistic; the first GPU step shows 50 ms against bvh's 2 ms.
  AutoSelector selector(true, [] { return std::optional<GpuCost>(GpuCost{0.1, 0.0}); });
  std::string reason;
  const auto chosen =
      Steps(selector, {10, 1000}, {{"bvh", 2.0}, {"far/id-buffer/256", 50.0}}, 8, &reason);
  EXPECT_EQ(chosen[2], "far/id-buffer/256");
  EXPECT_EQ(chosen[3], "far/id-buffer/256");
  for (size_t i = 4; i < chosen.size(); ++i) EXPECT_EQ(chosen[i], "bvh");
  // The reason names what ran and what the GPU step predicts for the others (half its time).
  EXPECT_NE(reason.find("auto: bvh is the fastest measured (2.00 ms); far/id-buffer/256 "
                        "measured 50 ms; not tried (predicted over 3x the best): "
                        "far/occlusion-query/256, far/id-buffer/1024, far/occlusion-query/1024, "
                        "far-exact-offset/id-buffer/256 25 ms"),
            std::string::npos)
      << reason;
}

// A GPU with the gpu method probed: it is the second candidate, and chosen where it measures
// fastest; the reason says on how many CPU threads the times were measured.
TEST(AutoSelectorTest, TheGpuMethodIsTriedSecondAndChosenWhereFastest) {
  GpuCost probe{5.0, 0.01};
  probe.compute_fixed_ms = 0.3;
  probe.compute_ms_per_triangle = 1e-6;
  AutoSelector selector(
      true, [&] { return std::optional<GpuCost>(probe); }, 16);
  std::string reason;
  const auto chosen = Steps(selector, {150, 40000}, {{"bvh", 2.0}, {"gpu", 0.4}}, 8, &reason);
  EXPECT_EQ(chosen[0], "bvh");
  EXPECT_EQ(chosen[2], "gpu");
  EXPECT_EQ(chosen.back(), "gpu");
  EXPECT_NE(reason.find("auto: gpu is the fastest measured (0.40 ms, CPU stages on 16 threads); "
                        "bvh measured 2.00 ms"),
            std::string::npos)
      << reason;
}

// Where the gpu method is predicted far slower (a software renderer, a large scene), it is not
// tried; where its probe did not run, it is no candidate; where its step failed, it is left out.
TEST(AutoSelectorTest, TheGpuMethodIsSkippedWhenHopelessUnprobedOrFailed) {
  GpuCost slow{5.0, 0.03};
  slow.compute_fixed_ms = 2.0;
  slow.compute_ms_per_triangle = 1e-3;  // 42 ms predicted for 40K triangles
  AutoSelector hopeless(true, [&] { return std::optional<GpuCost>(slow); });
  std::string reason;
  for (const std::string& name : Steps(hopeless, {150, 40000}, {{"bvh", 5.0}}, 6, &reason))
    EXPECT_EQ(name, "bvh");
  EXPECT_NE(reason.find("gpu 42 ms"), std::string::npos) << reason;

  AutoSelector unprobed(true, [] { return std::optional<GpuCost>(GpuCost{5.0, 0.03}); });
  for (const std::string& name : Steps(unprobed, {150, 40000}, {{"bvh", 5.0}}, 6))
    EXPECT_NE(name, "gpu");

  GpuCost fast{5.0, 0.03};
  fast.compute_fixed_ms = 0.1;
  fast.compute_ms_per_triangle = 0.0;
  AutoSelector failing(true, [&] { return std::optional<GpuCost>(fast); });
  std::string first;
  EXPECT_EQ(failing.Choose({150, 40000}, &first).Name(), "bvh");
  failing.Record({Method::kBvh, QueryMechanism::kIdBuffer, 0}, 5.0);
  const Candidate tried = failing.Choose({150, 40000}, &first);
  failing.Record(tried, 5.0);
  const Candidate gpu = failing.Choose({150, 40000}, &first);
  ASSERT_EQ(gpu.Name(), "gpu");
  failing.Exclude(gpu);
  for (const std::string& name : Steps(failing, {150, 40000}, {{"bvh", 5.0}}, 6))
    EXPECT_NE(name, "gpu");
}

// Cores shared with other sessions or simulators: bvh's step is fast on 16 threads but keeps
// them busy (12 ms of CPU for 1.7 ms); gpu's takes 1.9 ms and 1.9 ms of CPU. Alone (a share of
// 16 cores) bvh wins; on a 1-core share gpu does.
TEST(AutoSelectorTest, CpuTimeOverTheShareDecidesOnSharedCores) {
  GpuCost probe{5.0, 0.03};
  probe.compute_fixed_ms = 1.0;
  probe.compute_ms_per_triangle = 0.0;
  for (double share : {16.0, 1.0}) {
    AutoSelector selector(
        true, [&] { return std::optional<GpuCost>(probe); }, 16);
    selector.set_cpu_share(share);
    std::string reason;
    for (int i = 0; i < 8; ++i) {
      const Candidate c = selector.Choose({150, 40000}, &reason);
      if (c.Name() == "bvh")
        selector.Record(c, 1.7, 12.0);
      else if (c.Name() == "gpu")
        selector.Record(c, 1.9, 1.9);
      else
        selector.Record(c, 100, 100);
    }
    const Candidate chosen = selector.Choose({150, 40000}, &reason);
    EXPECT_EQ(chosen.Name(), share == 16.0 ? "bvh" : "gpu") << reason;
    if (share == 1.0) {
      EXPECT_NE(reason.find("CPU time over a 1.0-core share"), std::string::npos) << reason;
      EXPECT_NE(reason.find("bvh measured 12 ms"), std::string::npos) << reason;
    }
  }
}

TEST(AutoSelectorTest, RecalibratesWhenTheSceneGrowsOrTheChoiceDrifts) {
  AutoSelector selector(true, [] { return std::optional<GpuCost>(GpuCost{1.0, 0.001}); });
  // Small scene: the GPU (1.1 ms predicted, 1 ms measured) wins over bvh (5 ms).
  auto chosen = Steps(selector, {4, 100}, {{"bvh", 5.0}, {"far/id-buffer/256", 1.0}}, 14);
  EXPECT_EQ(chosen.back(), "far/id-buffer/256");
  // The scene grows 100x: calibration starts again from bvh, and the GPU is tried again only
  // if its prediction allows it (1 + 0.001 * 10000 = 11 ms > 3 x 2 ms: no).
  chosen = Steps(selector, {400, 10000}, {{"bvh", 2.0}, {"far/id-buffer/256", 1.0}}, 4);
  EXPECT_EQ(chosen[0], "bvh");
  EXPECT_EQ(chosen.back(), "bvh");
  // bvh drifts to 10 ms (> 2x its 2 ms): re-calibrated, and the GPU gets its chance again.
  chosen = Steps(selector, {400, 10000}, {{"bvh", 10.0}, {"far/id-buffer/256", 1.0}}, 12);
  EXPECT_EQ(chosen.back(), "far/id-buffer/256");
}

// A session's gpu steps at calibration queued behind other sessions' one-off GPU setup (16
// clients starting together on one daemon): gpu measured 40 ms where it takes 4, so bvh (11 ms)
// won. A periodic recheck soon after runs gpu again (against bvh's moving average) and keeps it;
// the next rechecks, which keep the choice, come twice as far apart each time.
TEST(AutoSelectorTest, ATransientLossIsRecheckedSoonThenLessOften) {
  GpuCost probe{50.0, 0.03};  // the raster configurations: never tried
  probe.compute_fixed_ms = 2.0;
  probe.compute_ms_per_triangle = 0.0;
  AutoSelector selector(true, [&] { return std::optional<GpuCost>(probe); });
  int gpu_runs = 0;
  std::vector<std::string> chosen;
  std::vector<int> calibrations;  // the steps at which bvh was tried (each recheck tries it)
  for (int i = 0; i < 600; ++i) {
    std::string reason;
    const Candidate c = selector.Choose({150, 40000}, &reason);
    chosen.push_back(c.Name());
    if (c.Name() == "bvh") {
      if (selector.trying()) calibrations.push_back(i);
      selector.Record(c, 11.0);
    } else {
      ASSERT_EQ(c.Name(), "gpu") << reason;
      selector.Record(c, ++gpu_runs <= 2 ? 40.0 : 4.0);
    }
  }
  // bvh twice (its first run on the objects runs again), gpu twice (40 ms): bvh wins...
  EXPECT_EQ(chosen[4], "bvh");
  // ...until the first recheck, 32 steps later, when gpu takes over.
  EXPECT_EQ(chosen.back(), "gpu");
  ASSERT_GE(calibrations.size(), 4u);
  const int taken_over =
      static_cast<int>(std::find(chosen.begin() + 4, chosen.end(), "gpu") - chosen.begin());
  EXPECT_LE(taken_over, 4 + AutoSelector::kFirstRecheckSteps + 2);
  // That recheck ran gpu against bvh's moving average: bvh was not tried again.
  EXPECT_GT(calibrations[2], taken_over);
  // Later rechecks (each a bvh step) keep gpu and come at growing intervals.
  std::vector<int> later(calibrations.begin() + 2, calibrations.end());
  ASSERT_GE(later.size(), 3u);
  for (size_t k = 2; k < later.size(); ++k)
    EXPECT_GT(later[k] - later[k - 1], later[k - 1] - later[k - 2]);
  EXPECT_LE(later.size(), 6u);  // 600 steps: 32 + 64 + 128 + 256 apart, not one every 32
}

// Runs `steps` choices on the scenes `scene(i)` gives; a candidate's step costs
// `cost(name, first)`, `first` when it is its first step on the scene's set of objects.
std::vector<std::string> StepsOn(AutoSelector& selector, const std::function<SceneSize(int)>& scene,
                                 const std::function<double(const std::string&, bool)>& cost,
                                 int steps, std::string* last_reason) {
  std::map<std::string, uint64_t> ran_on;
  std::vector<std::string> chosen;
  for (int i = 0; i < steps; ++i) {
    const SceneSize size = scene(i);
    const Candidate c = selector.Choose(size, last_reason);
    const bool first = !ran_on.contains(c.Name()) || ran_on[c.Name()] != size.structure;
    ran_on[c.Name()] = size.structure;
    selector.Record(c, cost(c.Name(), first));
    chosen.push_back(c.Name());
  }
  return chosen;
}

TEST(AutoSelectorTest, TheOneOffWorkOfAFirstRunOnNewObjectsDoesNotDecide) {
  // bvh builds its hierarchies on its first step (40 ms, then 3 ms a step); each GPU
  // configuration uploads the geometry on its first (10 ms, then 4 ms). Counting first runs
  // would choose the GPU at 4 ms over bvh's 3.
  AutoSelector selector(true, [] { return std::optional<GpuCost>(GpuCost{1.0, 0.0001}); });
  const auto cost = [](const std::string& name, bool first) {
    if (name == "bvh") return first ? 40.0 : 3.0;
    return first ? 10.0 : 4.0;
  };
  std::string reason;
  auto chosen = StepsOn(
      selector,
      [](int) {
        return SceneSize{10, 1000, 0};
      },
      cost, 16, &reason);
  EXPECT_EQ(chosen[0], "bvh");
  EXPECT_EQ(chosen[1], "bvh");  // again: its first run did one-off work
  EXPECT_EQ(chosen.back(), "bvh");
  EXPECT_NE(reason.find("auto: bvh is the fastest measured (3.00 ms)"), std::string::npos)
      << reason;
  // One more object (10%: no re-calibration): bvh's first step on it builds one hierarchy, 40
  // ms again, which is no step's steady cost: its average stays, and it stays chosen.
  chosen = StepsOn(
      selector,
      [](int) {
        return SceneSize{11, 1100, 1};
      },
      cost, 3, &reason);
  for (const std::string& name : chosen) EXPECT_EQ(name, "bvh");
  EXPECT_NE(reason.find("auto: bvh is the fastest measured (3.00 ms)"), std::string::npos)
      << reason;
}

TEST(AutoSelectorTest, ObjectsChangingAtEveryStepCostOneExtraRunAtMost) {
  AutoSelector selector(false, [] { return std::optional<GpuCost>(); });
  std::string reason;
  const auto chosen = StepsOn(
      selector,
      [](int i) {
        return SceneSize{10, 1000, static_cast<uint64_t>(i)};
      },
      [](const std::string&, bool first) { return first ? 7.0 : 5.0; }, 2, &reason);
  EXPECT_EQ(chosen, (std::vector<std::string>{"bvh", "bvh"}));
  std::string next;
  selector.Choose(SceneSize{10, 1000, 2}, &next);
  EXPECT_NE(next.find("auto: bvh is the fastest measured (7.00 ms)"), std::string::npos) << next;
}

}  // namespace
}  // namespace far::internal
