// What this measures, and why:
// - BM_SweepAndPrune_*: one Update of the incremental sweep-and-prune over n boxes when the scene
//   moves coherently (small jitter: the insertion sort does few swaps), when it does not move,
//   and from scratch (a new SweepAndPrune each time). The incremental path is the reason SAP
//   keeps its endpoint lists between steps; this shows what that buys.
// - BM_ExactStage_*: the exact stage on two interpenetrating triangle soups, with the per-object
//   sort-and-sweep prefilter (RunExactTests) against the all-pairs brute force
//   (BruteForceReference), on 1 and on all threads.
// - BM_SortContacts: the merge's sort of a step's contacts (far::internal::SortPairs, a radix
//   sort, against std::sort) for n contacts between 13 objects of up to 100K triangles, right
//   after the thread slept range(1) us, as a step's merge runs after an idle gap (manual time:
//   the sort only).
// Run:
//   build/<dir>/bench/pairs/far_pairs_benchmark --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "far/pairs/exact_stage.h"
#include "far/pairs/internal/pair_sort.h"
#include "far/pairs/sweep_and_prune.h"

namespace far {
namespace {

std::vector<SlotBox> RandomBoxes(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  // About 4 overlapping neighbours per box whatever n.
  const double extent = std::cbrt(static_cast<double>(n)) * 2.0;
  std::uniform_real_distribution<double> position(0, extent), size(0.2, 1.5);
  std::vector<SlotBox> boxes;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d lo(position(rng), position(rng), position(rng));
    boxes.push_back(
        {SlotAt(static_cast<size_t>(i)),
         Eigen::AlignedBox3d(lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng)))});
  }
  return boxes;
}

void Jitter(std::vector<SlotBox>& boxes, std::mt19937& rng, double amount) {
  std::uniform_real_distribution<double> jitter(-amount, amount);
  for (SlotBox& box : boxes) {
    const Eigen::Vector3d delta(jitter(rng), jitter(rng), jitter(rng));
    box.box_W = Eigen::AlignedBox3d(box.box_W.min() + delta, box.box_W.max() + delta);
  }
}

void BM_SweepAndPrune_Coherent(benchmark::State& state) {
  std::vector<SlotBox> boxes = RandomBoxes(static_cast<int>(state.range(0)), 1);
  std::mt19937 rng(2);
  SweepAndPrune sap;
  sap.Update(boxes);
  size_t swaps = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Jitter(boxes, rng, 0.01);
    state.ResumeTiming();
    benchmark::DoNotOptimize(sap.Update(boxes));
    swaps += sap.last_swaps();
  }
  state.counters["swaps"] =
      benchmark::Counter(static_cast<double>(swaps), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_SweepAndPrune_Coherent)->Arg(1000)->Arg(10000)->Arg(100000);

void BM_SweepAndPrune_Static(benchmark::State& state) {
  const std::vector<SlotBox> boxes = RandomBoxes(static_cast<int>(state.range(0)), 1);
  SweepAndPrune sap;
  sap.Update(boxes);
  for (auto _ : state) benchmark::DoNotOptimize(sap.Update(boxes));
}
BENCHMARK(BM_SweepAndPrune_Static)->Arg(1000)->Arg(10000)->Arg(100000);

void BM_SweepAndPrune_FromScratch(benchmark::State& state) {
  std::vector<SlotBox> boxes = RandomBoxes(static_cast<int>(state.range(0)), 1);
  std::mt19937 rng(2);
  for (auto _ : state) {
    state.PauseTiming();
    Jitter(boxes, rng, 0.01);
    state.ResumeTiming();
    SweepAndPrune sap;
    benchmark::DoNotOptimize(sap.Update(boxes));
  }
}
BENCHMARK(BM_SweepAndPrune_FromScratch)->Arg(1000)->Arg(10000)->Arg(100000);

// Two random triangle soups of n triangles each in the same cube.
struct Soups {
  std::vector<std::vector<Eigen::Vector3d>> positions;
  std::vector<std::vector<TriangleIndices>> triangles;
  std::vector<WorldObjectView> views;
};

Soups MakeSoups(int n) {
  std::mt19937 rng(3);
  const double extent = std::sqrt(static_cast<double>(n)) * 0.2;
  std::uniform_real_distribution<double> position(0, extent), corner(-0.3, 0.3);
  Soups soups;
  soups.positions.resize(2);
  soups.triangles.resize(2);
  for (int o = 0; o < 2; ++o) {
    for (int t = 0; t < n; ++t) {
      const Eigen::Vector3d center(position(rng), position(rng), position(rng));
      const auto base = static_cast<uint32_t>(soups.positions[o].size());
      for (int k = 0; k < 3; ++k) {
        soups.positions[o].push_back(center +
                                     Eigen::Vector3d(corner(rng), corner(rng), corner(rng)));
      }
      soups.triangles[o].push_back({base, base + 1, base + 2});
    }
  }
  for (uint32_t o = 0; o < 2; ++o) soups.views.push_back({soups.positions[o], soups.triangles[o]});
  return soups;
}

void BM_ExactStage_SortAndSweep(benchmark::State& state) {
  const Soups soups = MakeSoups(static_cast<int>(state.range(0)));
  ThreadPool pool(static_cast<int>(state.range(1)));
  const std::vector<SlotPair> pairs = {{SlotAt(0), SlotAt(1)}};
  ExactQuery query;
  query.objects = soups.views;
  query.object_pairs = pairs;
  query.max_distance = 0.05;
  size_t contacts = 0;
  for (auto _ : state) contacts = RunExactTests(query, pool).contacts.size();
  state.counters["contacts"] = static_cast<double>(contacts);
}
BENCHMARK(BM_ExactStage_SortAndSweep)
    ->Args({1000, 1})
    ->Args({10000, 1})
    ->Args({10000, 0})
    ->Args({100000, 0})
    ->Unit(benchmark::kMillisecond);

void BM_ExactStage_BruteForce(benchmark::State& state) {
  const Soups soups = MakeSoups(static_cast<int>(state.range(0)));
  ThreadPool pool(static_cast<int>(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(BruteForceReference(soups.views, 0.05, pool));
}
BENCHMARK(BM_ExactStage_BruteForce)
    ->Args({1000, 1})
    ->Args({10000, 0})
    ->Unit(benchmark::kMillisecond);

// range(0) contacts, range(1) us idle before each sort, range(2): 0 std::sort, 1 SortPairs.
void BM_SortContacts(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  const auto idle = std::chrono::microseconds(state.range(1));
  std::mt19937 rng(11);
  std::vector<SlotContact> input(n);
  for (SlotContact& p : input) {
    const size_t a = 1 + rng() % 13;
    p.object_a = SlotAt(a);
    p.object_b = SlotAt(a + 1 + rng() % 3);
    p.triangle_a = rng() % 100000;
    p.triangle_b = rng() % 3000;
  }
  for (auto _ : state) {
    std::vector<SlotContact> pairs = input;
    if (idle.count() > 0) std::this_thread::sleep_for(idle);
    const auto start = std::chrono::steady_clock::now();
    if (state.range(2) == 0) {
      std::sort(pairs.begin(), pairs.end());
    } else {
      internal::SortPairs(pairs);
    }
    state.SetIterationTime(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    benchmark::DoNotOptimize(pairs.data());
  }
}
BENCHMARK(BM_SortContacts)
    ->ArgsProduct({{620, 1500, 20000}, {0, 6000}, {0, 1}})
    ->ArgNames({"n", "idle_us", "radix"})
    ->Iterations(100)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace far

BENCHMARK_MAIN();
