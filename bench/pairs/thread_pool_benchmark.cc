// What this measures, and why: one ParallelFor of 64 chunks of 10 us of work on 2 threads (the
// calling thread and one worker), right after the caller slept for `idle_us` (range 0), as a
// pipeline step does after a simulator's own work or far-study's other configurations. The
// counter `one_thread` is the fraction of loops in which the worker ran no chunk: it woke on
// the caller's CPU and waited there while the caller did the whole loop (ThreadPool keeps its
// workers off the caller's CPU for this reason; on the 2-vCPU development VM, 32-42% of the
// loops after 1-6 ms idle ran on one thread before it did). Time is the loop's wall time only.
// Run:
//   build/<dir>/bench/pairs/far_thread_pool_benchmark --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true

#include <atomic>
#include <chrono>
#include <thread>

#include <benchmark/benchmark.h>

#include "far/base/thread_pool.h"

namespace far {
namespace {

using Clock = std::chrono::steady_clock;

void SpinFor(std::chrono::microseconds duration) {
  const auto end = Clock::now() + duration;
  while (Clock::now() < end) {
  }
}

void BM_ParallelForAfterIdle(benchmark::State& state) {
  const auto idle = std::chrono::microseconds(state.range(0));
  ThreadPool pool(2);
  int64_t loops = 0, one_thread = 0;
  for (auto _ : state) {
    std::this_thread::sleep_for(idle);
    const std::thread::id caller = std::this_thread::get_id();
    std::atomic<bool> worker_ran = false;
    const auto start = Clock::now();
    pool.ParallelFor(64, 1, [&](size_t, size_t) {
      if (std::this_thread::get_id() != caller) worker_ran = true;
      SpinFor(std::chrono::microseconds(10));
    });
    state.SetIterationTime(std::chrono::duration<double>(Clock::now() - start).count());
    ++loops;
    if (!worker_ran) ++one_thread;
  }
  state.counters["one_thread"] = static_cast<double>(one_thread) / static_cast<double>(loops);
}
BENCHMARK(BM_ParallelForAfterIdle)
    ->Arg(0)
    ->Arg(1000)
    ->Arg(6000)
    ->Iterations(200)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace far

BENCHMARK_MAIN();
