// far-deadline-study: how far past its deadline a step of the heaviest legal scene stops, per
// method and mechanism, and where it was when it noticed (issue 41: "a step stops within 1 s,
// or 5%, of its deadline in every stage"). In process, one far::Pipeline per configuration (as
// a daemon session has): the scene is loaded, then steps run with a deadline `--deadline-ms`
// after their start. Every check of the step's StepControl (StepControl::Check, on any thread)
// is timed: the longest span between two checks is what bounds how late a step can notice its
// deadline, and the stage that span ended in is where a check is missing.
//   far-deadline-study [--triangles 1940000] [--deadline-ms 1000] [--methods aabb,bvh,far,...]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "far/base/step_control.h"
#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// One configuration to step: "far/occlusion-query/1024" and the like.
struct Config {
  far::StepRequest request;
  std::string name;
};

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    if (comma > start) parts.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  return parts;
}

// "method[/mechanism[/resolution]]", e.g. "far/occlusion-query/1024", "bvh".
std::optional<Config> ParseConfig(const std::string& text, double distance) {
  const std::vector<std::string> parts = [&] {
    std::vector<std::string> p;
    size_t start = 0;
    while (start <= text.size()) {
      const size_t slash = std::min(text.find('/', start), text.size());
      p.push_back(text.substr(start, slash - start));
      start = slash + 1;
    }
    return p;
  }();
  Config config;
  config.name = text;
  const auto method = far::ParseMethod(parts[0]);
  if (!method) return std::nullopt;
  config.request.method = *method;
  config.request.output = far::Output::kContacts;
  if (distance > 0) config.request.distance = distance;
  if (parts.size() > 1) {
    const auto mechanism = far::ParseMechanism(parts[1]);
    if (!mechanism) return std::nullopt;
    config.request.mechanism = *mechanism;
  }
  if (parts.size() > 2) config.request.resolution = std::stoi(parts[2]);
  return config;
}

// The checks of one step: the longest span without one, and the stage it ended in.
struct CheckTrace {
  std::mutex mutex;
  Clock::time_point last;
  double longest_ms = 0;
  std::string longest_stage = "-";
  far::Stage stage = far::Stage::kUpdate;
  int64_t checks = 0;

  void Note(Clock::time_point now) {
    std::lock_guard lock(mutex);
    ++checks;
    const double gap = Ms(now - last);
    if (gap > longest_ms) {
      longest_ms = gap;
      longest_stage = std::string(far::ToString(stage));
    }
    last = now;
  }
};

struct StepOutcome {
  double ms = 0;
  double past_deadline_ms = 0;
  std::string what;
  double longest_gap_ms = 0;
  std::string gap_stage;
  int64_t checks = 0;
};

StepOutcome RunStep(far::Pipeline& pipeline, const far::StepRequest& request, double deadline_ms) {
  CheckTrace trace;
  far::StepControl control;
  const Clock::time_point start = Clock::now();
  trace.last = start;
  control.deadline = start + std::chrono::microseconds(static_cast<int64_t>(deadline_ms * 1000));
  control.slow_after = start;  // every check calls on_slow: the trace
  control.on_slow = [&trace] { trace.Note(Clock::now()); };
  control.on_stage = [&trace](far::Stage stage) {
    trace.Note(Clock::now());
    std::lock_guard lock(trace.mutex);
    trace.stage = stage;
  };
  auto result = pipeline.Step(request, control);
  const Clock::time_point end = Clock::now();
  trace.Note(end);  // the span from the last check to the step's end
  StepOutcome outcome;
  outcome.ms = Ms(end - start);
  outcome.past_deadline_ms = Ms(end - control.deadline);
  outcome.what = result ? "finished" : result.error().message;
  outcome.longest_gap_ms = trace.longest_ms;
  outcome.gap_stage = trace.longest_stage;
  outcome.checks = trace.checks;
  return outcome;
}

}  // namespace

int main(int argc, char** argv) {
  int triangles = 1'940'000;
  double deadline_ms = 1000;
  double distance = 0;
  int steps = 2;
  int threads = 0;
  std::string methods = "aabb,bvh,fcl,far/id-buffer/1024,far/occlusion-query/1024";
  CLI::App app{"far-deadline-study: how far past its deadline a heavy step stops"};
  app.add_option("--triangles", triangles, "ScalingScene size")->capture_default_str();
  app.add_option("--deadline-ms", deadline_ms, "each step's deadline after its start")
      ->capture_default_str();
  app.add_option("--distance", distance, "> 0: contacts searched within this distance")
      ->capture_default_str();
  app.add_option("--steps", steps, "steps per configuration (the first builds)")
      ->capture_default_str();
  app.add_option("--threads", threads, "CPU pool threads (0: all cores)")->capture_default_str();
  app.add_option("--methods", methods, "configurations: method[/mechanism[/resolution]],...")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const far::Scene scene = far::scenes::ScalingScene(29, triangles, 1);
  int64_t count = 0;
  size_t largest = 0;
  for (const auto& object : scene.objects) {
    count += object.mesh.triangles.size();
    largest = std::max(largest, object.mesh.triangles.size());
  }
  std::printf(
      "scene: ScalingScene, %zu objects, %lld triangles (the largest object: %zu); deadline %.0f "
      "ms\n\n",
      scene.objects.size(), static_cast<long long>(count), largest, deadline_ms);
  std::printf(
      "| configuration | step | ms | past the deadline, ms | answer | longest span without a "
      "check, ms | in stage | checks |\n");
  std::printf("| --- | --: | --: | --: | --- | --: | --- | --: |\n");
  for (const std::string& text : Split(methods)) {
    const auto config = ParseConfig(text, distance);
    if (!config) {
      std::fprintf(stderr, "far-deadline-study: bad configuration '%s'\n", text.c_str());
      return 2;
    }
    far::PipelineOptions options;
    options.num_threads = threads;
    options.use_gl = far::NeedsGl(config->request.method);
    auto pipeline = far::Pipeline::Create(options);
    if (!pipeline) {
      std::fprintf(stderr, "far-deadline-study: %s\n", pipeline.error().message.c_str());
      return 1;
    }
    if (auto ok = (*pipeline)->LoadScene(scene); !ok) {
      std::fprintf(stderr, "far-deadline-study: %s\n", ok.error().message.c_str());
      return 1;
    }
    for (int step = 1; step <= steps; ++step) {
      const StepOutcome o = RunStep(**pipeline, config->request, deadline_ms);
      std::printf("| %s | %d | %.0f | %.0f | %s | %.0f | %s | %lld |\n", config->name.c_str(), step,
                  o.ms, o.past_deadline_ms, o.what.c_str(), o.longest_gap_ms, o.gap_stage.c_str(),
                  static_cast<long long>(o.checks));
      std::fflush(stdout);
    }
  }
  return 0;
}
