// far-step-profile: the time of every step of one far-study scene with one CPU method, in
// process (no GL), or with the gpu method (GL), with the counts a hierarchy change moves
// (triangle pairs at leaves, exact tests). For profiling a kernel change with `perf record`,
// and for comparing two builds of it step by step on the same scene; far-study is the
// interleaved study of record. For gpu, stages_ms also has the CPU's part of its GPU stage:
// gl_prepare (issuing the uploads and kernels) and gl_passes (waiting, reading back).
//   far-step-profile --scene breaking --method bvh --steps 4
//   far-step-profile --scene paper-leaves --method gpu --steps 40
//   perf record -g far-step-profile --scene breaking --steps 4 --repeat 50 --repeat-from 3
//   far-step-profile --scene breaking --repeat 50 --repeat-from 3 --cold   (first-run caches)
//   far-step-profile --scene scaling-5000 --distance-fraction 0.001  (the distance pass)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "study_run.h"
#include "study_scenes.h"
#include <CLI/CLI.hpp>

#include "far/pipeline/pipeline.h"

namespace {

using Clock = std::chrono::steady_clock;

// Writes a buffer larger than the last-level cache (32 MiB on the EPYC this was written on),
// evicting the step's data.
void EvictCaches() {
  static std::vector<char> buffer(64 << 20);
  for (size_t i = 0; i < buffer.size(); i += 64) buffer[i]++;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"far-step-profile: time per step of one CPU method on one far-study scene"};
  std::string scene_name = "breaking", method_name = "bvh";
  far_study::SceneOptions scene_options;
  scene_options.bunny_path = FAR_STUDY_DATA_DIR "/bunny.obj";
  int threads = 0, repeat = 1, repeat_from = 0;
  app.add_option("--scene", scene_name,
                 "a far-study scene, built as far-study builds it: soup, bunnies, leaves, "
                 "paper-leaves, breaking, paper-bunnies, scaling-<triangles>")
      ->capture_default_str();
  app.add_option("--method", method_name, "a CPU method (bvh, aabb, fcl, exact) or gpu")
      ->capture_default_str();
  app.add_option("--steps", scene_options.steps, "measured steps (far-study's --steps)")
      ->capture_default_str();
  app.add_option("--threads", threads, "CPU pool threads (0: hardware)")->capture_default_str();
  app.add_option("--repeat", repeat,
                 "run each step's Step this many times on the same updates (repeat_ms: their "
                 "median), for enough perf samples of one step")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--repeat-from", repeat_from, "repeat only steps from this one on")
      ->capture_default_str();
  int idle_ms = 0;
  app.add_option("--idle-ms", idle_ms,
                 "sleep this long before each step, as a simulator's own work would between "
                 "steps (far-study's other configurations run there): the cores go idle and the "
                 "caches cold")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  bool cold = false;
  app.add_flag("--cold", cold,
               "write a 64 MiB buffer before each repeat, so that every repeat starts with caches "
               "as cold as a first run's (a run's repeats otherwise find the step's data cached)");
  double distance_fraction = 0;
  app.add_option("--distance-fraction", distance_fraction,
                 "ask for the distance pairs too, with D this fraction of the diagonal of the "
                 "scene's world box (far-study's --distance-fraction; 0: contacts only)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--bunny", scene_options.bunny_path, "bunny mesh")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const auto method = far::ParseMethod(method_name);
  const bool gpu = method && *method == far::Method::kGpu;
  const bool cpu = method && (*method == far::Method::kBvh || *method == far::Method::kAabb ||
                              *method == far::Method::kFcl || *method == far::Method::kExact);
  if (!cpu && !gpu) {
    std::fprintf(stderr, "far-step-profile: --method must be bvh, aabb, fcl, exact or gpu\n");
    return 2;
  }
  auto study_scene = far_study::MakeStudyScene(scene_name, scene_options);
  if (!study_scene.ok()) {
    std::fprintf(stderr, "far-step-profile: %s\n", study_scene.error().message.c_str());
    return 2;
  }
  const far::Scene& scene = study_scene->scene;

  far::PipelineOptions options;
  options.use_gl = gpu;
  options.num_threads = threads;
  auto pipeline = far::Pipeline::Create(options);
  if (!pipeline.ok()) {
    std::fprintf(stderr, "far-step-profile: %s\n", pipeline.error().message.c_str());
    return 1;
  }
  if (auto loaded = (*pipeline)->LoadScene(scene); !loaded.ok()) {
    std::fprintf(stderr, "far-step-profile: %s\n", loaded.error().message.c_str());
    return 1;
  }
  far::StepRequest request;
  request.method = *method;
  if (distance_fraction > 0) {
    if (*method == far::Method::kFcl) {
      std::fprintf(stderr, "far-step-profile: fcl answers no distance queries\n");
      return 2;
    }
    request.distance = distance_fraction * study_scene->diagonal;
    request.output = far::Output::kDistancePairs;
  }
  std::printf(
      "step,ms,repeat_ms,contacts,distance_pairs,object_pairs,pairs_considered,pairs_tested,"
      "node_pairs,leaf_descents,leaf_descent_nodes,leaf_pairs,boxes_met,stages_ms\n");
  for (size_t s = 0; s <= scene.frames.size(); ++s) {
    if (idle_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(idle_ms));
    const auto start = Clock::now();
    if (s > 0) {
      if (auto ok = (*pipeline)->Apply(far_study::ToUpdates(scene.frames[s - 1])); !ok.ok()) {
        std::fprintf(stderr, "far-step-profile: %s\n", ok.error().message.c_str());
        return 1;
      }
    }
    auto result = (*pipeline)->Step(request);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (!result.ok()) {
      std::fprintf(stderr, "far-step-profile: step %zu: %s\n", s, result.error().message.c_str());
      return 1;
    }
    // The same step again (no new updates): the median of the repeats' Step times.
    std::vector<double> repeats;
    for (int r = 1; r < repeat && static_cast<int>(s) >= repeat_from; ++r) {
      if (cold) EvictCaches();
      const auto again = Clock::now();
      if (!(*pipeline)->Step(request).ok()) return 1;
      repeats.push_back(std::chrono::duration<double, std::milli>(Clock::now() - again).count());
    }
    std::sort(repeats.begin(), repeats.end());
    const double repeat_ms = repeats.empty() ? ms : repeats[repeats.size() / 2];
    // The first run's stage timers, "name=ms" separated by spaces.
    std::string stages;
    for (const far::StageStats& stage : result->stats.stages) {
      char ms_text[32];
      std::snprintf(ms_text, sizeof ms_text, "%.3f", stage.ms);
      stages +=
          (stages.empty() ? "" : " ") + std::string(far::ToString(stage.stage)) + "=" + ms_text;
    }
    if (gpu) {
      char gl_text[64];
      std::snprintf(gl_text, sizeof gl_text, " gl_prepare=%.3f gl_passes=%.3f",
                    result->stats.gl_prepare_ms, result->stats.gl_passes_ms);
      stages += gl_text;
    }
    const far::DescentCounters& descent = result->stats.descent;
    std::printf("%zu,%.3f,%.3f,%zu,%zu,%lld,%lld,%lld,%lld,%lld,%lld,%lld,%lld,%s\n", s, ms,
                repeat_ms, result->contacts.size(), result->distance_pairs.size(),
                static_cast<long long>(result->stats.object_pairs),
                static_cast<long long>(result->stats.pairs_considered),
                static_cast<long long>(result->stats.pairs_tested),
                static_cast<long long>(descent.node_pairs),
                static_cast<long long>(descent.leaf_descents),
                static_cast<long long>(descent.leaf_descent_nodes),
                static_cast<long long>(descent.leaf_pairs),
                static_cast<long long>(descent.boxes_met), stages.c_str());
  }
  return 0;
}
