// Ring ingest throughput for deformable objects' vertex updates: a client writes set_vertices
// records into a session's update ring and the daemon's UpdateReader drains them (copy out of
// shared memory, framing checks, validation of every double, conversion to far's types).
// Bytes per second count the vertex payload (24 bytes per vertex). Same process, one thread:
// the daemon-side cost is what bounds ingest (the writer is a memcpy).
//   build/release/bench/protocol/far_ring_ingest_benchmark --benchmark_repetitions=10
// (add --glibc-default-malloc last to measure without the daemon's malloc settings)
#include <malloc.h>

#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "far/protocol/ring_records.h"
#include "far/protocol/shm_segment.h"

namespace {

using far::protocol::ShmSegment;

void BM_RingIngest_SetVertices(benchmark::State& state) {
  const auto vertices = static_cast<size_t>(state.range(0));
  const int records_per_batch = static_cast<int>(state.range(1));
  far::protocol::SegmentOptions options;
  options.update_ring_bytes = uint64_t{64} << 20;
  options.reply_ring_bytes = uint64_t{64} << 10;
  auto segment = ShmSegment::Create(4242, options);
  if (!segment) {
    state.SkipWithError(segment.error().message.c_str());
    return;
  }
  far::protocol::UpdateWriter writer((*segment)->update_ring());
  far::protocol::UpdateReader reader((*segment)->update_ring(), far::protocol::RingLimits{});
  // One deformable object must exist for the records to mean something; the reader validates
  // records on their own (scene checks are the daemon's), so ids need not be added here.
  std::vector<Eigen::Vector3d> p_MV(vertices);
  for (size_t i = 0; i < vertices; ++i) p_MV[i] = Eigen::Vector3d(0.001 * i, 1.0, -0.5 * i);
  for (auto _ : state) {
    for (int r = 0; r < records_per_batch; ++r) {
      if (!writer.SetVertices(static_cast<uint32_t>(r + 1), p_MV)) {
        state.SkipWithError("ring full");
        return;
      }
    }
    auto drained = reader.Drain(writer.last_sequence());
    if (!drained || drained->size() != static_cast<size_t>(records_per_batch)) {
      state.SkipWithError(drained ? "short drain" : drained.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(drained->data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * records_per_batch *
                          static_cast<int64_t>(vertices * 24));
}
// (vertices per record, records per step): leaves of 50 vertices, meshes of 10k and 100k.
BENCHMARK(BM_RingIngest_SetVertices)
    ->Args({50, 200})
    ->Args({10'000, 8})
    ->Args({100'000, 2})
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  // As far-daemon does at start-up (server/src/main.cc): large buffers come from the heap and
  // are reused, instead of fresh zero-filled pages from mmap for every record.
  if (argc > 1 && std::string(argv[argc - 1]) == "--glibc-default-malloc") {
    --argc;
  } else {
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
