// The two ways to ask the GPU "is this primitive fully visible" (docs/culling.md), on fixed scenes:
// per-primitive occlusion queries (the paper) against the ID buffer (a fixed number of draws per
// axis). Backs far-study's first bar ("ID buffer at least 4x faster than occlusion queries at
// 20k+ primitives") with a kernel-level ratio: both benchmarks run FAR (UOBB offsets) up to the
// primitive PCS, object level and sub-object level, at 1024 x 1024, on two fixed 20,000-triangle
// scenes: scene:0, two interpenetrating spheres of 10,000 triangles each (all 20,000 enter the
// sub-object pass; large closed surfaces, fill-heavy), and scene:1, 40 clusters of 500 small
// random triangles (a few pixels each: per-primitive overhead dominates). The scenes are static,
// so after the first iteration no pieces are rebuilt or uploaded: what is timed is the culling
// passes themselves. Counters: queries, draws and PCS triangles of the last step. "CPU" is the
// CPU time of the whole process (llvmpipe's rasterizer threads included): on a machine shared
// with other work it is the steadier measure of the work done; "Time" is wall clock.
//   far_culling_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
// --gl-platform=auto|device|surfaceless (ours, not Google Benchmark's) picks the EGL platform;
// device makes a GPU run fail instead of falling back to llvmpipe's surfaceless platform.

#include <cstdio>
#include <memory>
#include <vector>

#include "gl_platform_flag.h"
#include "test_scenes.h"
#include <benchmark/benchmark.h>

#include "far/model/step_request.h"
#include "far/pipeline/pipeline.h"

namespace {

constexpr int kResolution = 1024;
far::GlPlatform g_platform = far::GlPlatform::kAuto;  // --gl-platform

enum Scene : int64_t { kSpheres = 0, kSoup = 1 };

// kSpheres: two spheres of radius 1, 2 * 50 * 100 = 10,000 triangles each, centers 1.2 apart
// (closed surfaces that fill most of the viewport). kSoup: 40 clusters of 500 random triangles
// of about 8 pixels (a few pixels of fill each: per-primitive overhead dominates).
std::unique_ptr<far::Pipeline> MakeScene(int64_t scene) {
  far::PipelineOptions options;
  options.platform = g_platform;
  auto pipeline = far::Pipeline::Create(options);
  if (!pipeline.ok()) {
    std::fprintf(stderr, "far_culling_benchmark: %s\n", pipeline.error().message.c_str());
    return nullptr;
  }
  if (scene == kSpheres) {
    for (uint32_t id : {1u, 2u}) {
      const Eigen::Vector3d center(id == 1 ? -0.6 : 0.6, 0.05 * id, 0.0);
      far::Mesh mesh = far::testing::SphereMesh(center, 1.0, 50, 100);
      if (!(*pipeline)->AddObject(id, std::move(mesh), far::Motion::kStatic).ok()) return nullptr;
    }
  } else {
    // Made once and shared by both benchmarks (the generator is deterministic per seed).
    static const std::vector<far::SceneObject> soup =
        far::testing::RandomSoup(3, 40, 500, 40.0, 0.4);
    for (const far::SceneObject& object : soup) {
      if (!(*pipeline)->AddObject(object.id, object.mesh, far::Motion::kStatic, object.X_WO).ok()) {
        return nullptr;
      }
    }
  }
  return std::move(*pipeline);
}

void RunCull(benchmark::State& state, far::QueryMechanism mechanism) {
  std::unique_ptr<far::Pipeline> pipeline = MakeScene(state.range(0));
  if (!pipeline) {
    state.SkipWithError("no GL context or bad scene");
    return;
  }
  far::StepRequest request;
  request.method = far::Method::kFar;
  request.mechanism = mechanism;
  request.resolution = kResolution;
  request.output = far::Output::kPrimitivePcs;
  // Warm-up: shaders, framebuffers, piece upload.
  if (!pipeline->Step(request).ok()) {
    state.SkipWithError("step failed");
    return;
  }
  far::StepStats stats;
  int64_t pcs = 0;
  for (auto _ : state) {
    auto result = pipeline->Step(request);
    if (!result.ok()) {
      state.SkipWithError(result.error().message.c_str());
      return;
    }
    stats = result->stats;
    pcs = 0;
    for (const auto& [id, triangles] : result->pcs_primitives)
      pcs += static_cast<int64_t>(triangles.size());
    benchmark::DoNotOptimize(pcs);
  }
  state.counters["queries"] = static_cast<double>(stats.queries);
  state.counters["draws"] = static_cast<double>(stats.draws);
  state.counters["pcs_triangles"] = static_cast<double>(pcs);
  state.counters["rendered"] = static_cast<double>(stats.primitives_rendered);
  state.SetLabel(pipeline->gl_renderer());
}

void BM_Cull_IdBuffer(benchmark::State& state) { RunCull(state, far::QueryMechanism::kIdBuffer); }
void BM_Cull_OcclusionQuery(benchmark::State& state) {
  RunCull(state, far::QueryMechanism::kOcclusionQuery);
}

BENCHMARK(BM_Cull_IdBuffer)
    ->ArgName("scene")
    ->Arg(kSpheres)
    ->Arg(kSoup)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_Cull_OcclusionQuery)
    ->ArgName("scene")
    ->Arg(kSpheres)
    ->Arg(kSoup)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  if (!far_study::TakeGlPlatformFlag(&argc, argv, &g_platform, "far_culling_benchmark")) return 2;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
