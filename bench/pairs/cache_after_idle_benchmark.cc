// What this measures, and why: how much slower the same memory reads get when the thread slept
// just before them, as a pipeline step's do after a simulator's own work or far-study's other
// configurations. One pass is 20,000 random 8-byte reads (independent, so the core overlaps
// their misses) over a working set of range(0) KiB, after sleeping range(1) us. A hierarchy step
// on a 5K-triangle scene touches about 4,000 cache lines of nodes, slabs, indices and
// vertices in its descent (scaling-5000, counted once by a scratch instrumentation), so a working
// set of 256 KiB to 8 MiB is the range that matters. If an idle gap alone makes the pass several
// times slower, the machine loses its caches while the thread sleeps (on a VM: the host runs
// something else on the core), and a step measured after idle time pays for its misses however
// compact the data. Time is the pass's wall time only. Run:
//   build/<dir>/bench/pairs/far_cache_after_idle_benchmark --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true

#include <chrono>
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

namespace far {
namespace {

using Clock = std::chrono::steady_clock;

void BM_RandomReadsAfterIdle(benchmark::State& state) {
  const size_t words = static_cast<size_t>(state.range(0)) * 1024 / sizeof(uint64_t);
  const auto idle = std::chrono::microseconds(state.range(1));
  constexpr size_t kReads = 20000;
  std::vector<uint64_t> data(words, 1);
  std::vector<uint32_t> where(kReads);
  std::mt19937 rng(7);
  std::uniform_int_distribution<uint32_t> pick(0, static_cast<uint32_t>(words - 1));
  for (uint32_t& w : where) w = pick(rng);
  for (auto _ : state) {
    if (idle.count() > 0) std::this_thread::sleep_for(idle);
    const auto start = Clock::now();
    uint64_t sum = 0;
    for (uint32_t w : where) sum += data[w];
    benchmark::DoNotOptimize(sum);
    state.SetIterationTime(std::chrono::duration<double>(Clock::now() - start).count());
  }
}
BENCHMARK(BM_RandomReadsAfterIdle)
    ->ArgsProduct({{256, 1024, 8192}, {0, 1000, 6000}})
    ->ArgNames({"KiB", "idle_us"})
    ->Iterations(200)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace far

BENCHMARK_MAIN();
