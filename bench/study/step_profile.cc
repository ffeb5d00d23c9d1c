// far-step-profile: the time of every step of one paper-scale scene with one CPU method, in
// process (no GL), with the counts a hierarchy change moves (triangle pairs at leaves, exact
// tests). For profiling a kernel change with `perf record`, and for comparing two builds of it
// step by step on the same scene; far-study is the interleaved study of record.
//   far-step-profile --scene breaking --method bvh --frames 8
//   perf record -g far-step-profile --scene breaking --frames 5 --repeat 50 --repeat-from 3
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "study_run.h"
#include <CLI/CLI.hpp>

#include "far/io/mesh_io.h"
#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"far-step-profile: time per step of one method on one paper-scale scene"};
  std::string scene_name = "breaking", method_name = "bvh";
  std::string bunny_path = FAR_STUDY_DATA_DIR "/bunny.obj";
  int frames = 8, threads = 0, repeat = 1, repeat_from = 0;
  uint64_t seed = 1;
  app.add_option("--scene", scene_name,
                 "leaves, breaking, bunnies, or a triangle count (the scaling family)")
      ->capture_default_str();
  app.add_option("--method", method_name, "a CPU method: bvh, aabb, fcl, exact")
      ->capture_default_str();
  app.add_option("--frames", frames, "frames of the scene (steps: frames)")->capture_default_str();
  app.add_option("--threads", threads, "CPU pool threads (0: hardware)")->capture_default_str();
  app.add_option("--seed", seed, "scene seed (1: far-study's paper-scale scenes)")
      ->capture_default_str();
  app.add_option("--repeat", repeat,
                 "run each step's Step this many times on the same updates (repeat_ms: their "
                 "median), for enough perf samples of one step")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--repeat-from", repeat_from, "repeat only steps from this one on")
      ->capture_default_str();
  app.add_option("--bunny", bunny_path, "bunny mesh")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const auto method = far::ParseMethod(method_name);
  const bool cpu = method && (*method == far::Method::kBvh || *method == far::Method::kAabb ||
                              *method == far::Method::kFcl || *method == far::Method::kExact);
  if (!cpu) {
    std::fprintf(stderr, "far-step-profile: --method must be bvh, aabb, fcl or exact\n");
    return 2;
  }
  far::Scene scene;
  if (scene_name == "leaves") {
    scene = far::scenes::PaperLeavesScene(seed, frames);
  } else if (scene_name == "breaking") {
    scene = far::scenes::BreakingScene(seed, frames);
  } else if (scene_name == "bunnies") {
    auto bunny = far::ReadMesh(bunny_path);
    if (!bunny.ok()) {
      std::fprintf(stderr, "far-step-profile: %s\n", bunny.error().message.c_str());
      return 1;
    }
    scene = far::scenes::BunniesScene(*bunny, 5, seed, frames);
  } else {
    int triangles = 0;
    try {
      triangles = std::stoi(scene_name);
    } catch (const std::exception&) {
      std::fprintf(stderr, "far-step-profile: unknown --scene '%s'\n", scene_name.c_str());
      return 2;
    }
    scene = far::scenes::ScalingScene(seed, triangles, frames);
  }

  far::PipelineOptions options;
  options.use_gl = false;
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
  std::printf("step,ms,repeat_ms,contacts,object_pairs,pairs_considered,pairs_tested\n");
  for (size_t s = 0; s <= scene.frames.size(); ++s) {
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
      const auto again = Clock::now();
      if (!(*pipeline)->Step(request).ok()) return 1;
      repeats.push_back(std::chrono::duration<double, std::milli>(Clock::now() - again).count());
    }
    std::sort(repeats.begin(), repeats.end());
    const double repeat_ms = repeats.empty() ? ms : repeats[repeats.size() / 2];
    std::printf("%zu,%.3f,%.3f,%zu,%lld,%lld,%lld\n", s, ms, repeat_ms, result->contacts.size(),
                static_cast<long long>(result->stats.object_pairs),
                static_cast<long long>(result->stats.pairs_considered),
                static_cast<long long>(result->stats.pairs_tested));
  }
  return 0;
}
