// What asking for the contact geometry costs (StepRequest::geometry): the same step with and
// without it, interleaved on the same scene state, on the demo scenes. Prints one table row per
// scene: medians with quartiles of the step time both ways, their ratio, the geometry stage's
// own time, and how many contacts, distance pairs and penetrations it described.
//
//   far_geometry_cost_study [--method bvh] [--threads 0] [--frames 4] [--repeats 5]
//                           [--distance D] [scene ...]      (default: paper-leaves breaking)

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "far/base/quantile.h"
#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace {

using far::StepRequest;
using far::StepResult;

struct Options {
  std::string method = "bvh";
  int threads = 0;
  int frames = 4;
  int repeats = 5;
  double distance = -1;  // < 0: contacts only
  std::vector<std::string> scenes;
};

Options Parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--method") {
      options.method = value();
    } else if (arg == "--threads") {
      options.threads = std::atoi(value().c_str());
    } else if (arg == "--frames") {
      options.frames = std::atoi(value().c_str());
    } else if (arg == "--repeats") {
      options.repeats = std::atoi(value().c_str());
    } else if (arg == "--distance") {
      options.distance = std::atof(value().c_str());
    } else {
      options.scenes.push_back(arg);
    }
  }
  if (options.scenes.empty()) options.scenes = {"paper-leaves", "breaking"};
  return options;
}

double StageMs(const StepResult& result, far::Stage stage) {
  for (const far::StageStats& s : result.stats.stages) {
    if (s.stage == stage) return s.ms;
  }
  return 0;
}

std::string Spread(const std::vector<double>& samples) {
  char text[96];
  std::snprintf(text, sizeof text, "%.2f [%.2f, %.2f]", far::Quantile(samples, 0.5),
                far::Quantile(samples, 0.25), far::Quantile(samples, 0.75));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = Parse(argc, argv);
  const auto method = far::ParseMethod(options.method);
  if (!method) {
    std::fprintf(stderr, "--method: unknown '%s'\n", options.method.c_str());
    return 2;
  }
  std::printf(
      "| scene | contacts | distance pairs | penetrations (closed) | step ms, no geometry "
      "| step ms, geometry | ratio | geometry stage ms |\n|---|---|---|---|---|---|---|---|\n");
  for (const std::string& name : options.scenes) {
    far::Scene scene;
    if (name == "paper-leaves") {
      scene = far::scenes::PaperLeavesScene(1, options.frames);
    } else if (name == "breaking") {
      scene = far::scenes::BreakingScene(1, options.frames);
    } else {
      std::fprintf(stderr, "unknown scene '%s' (paper-leaves, breaking)\n", name.c_str());
      return 2;
    }
    std::vector<double> plain_ms, geometry_ms, stage_ms;
    size_t contacts = 0, distance_pairs = 0, penetrations = 0, closed = 0;
    for (int frame = 0; frame < options.frames; ++frame) {
      far::PipelineOptions pipeline_options;
      pipeline_options.use_gl = false;
      pipeline_options.num_threads = options.threads;
      auto pipeline = far::Pipeline::Create(pipeline_options);
      auto objects = far::ObjectsAtStep(scene, static_cast<size_t>(frame));
      if (!pipeline.ok() || !objects.ok()) return 1;
      for (const far::SceneObject& object : *objects) {
        if (!(*pipeline)->AddObject(object.id, object.mesh, object.motion, object.X_WO).ok())
          return 1;
      }
      StepRequest request;
      request.method = *method;
      if (options.distance >= 0) {
        request.distance = options.distance;
        request.output = far::Output::kDistancePairs;
      }
      for (int r = 0; r < options.repeats; ++r) {
        // Interleaved, the order alternating, so that drift hits both alike.
        for (int k = 0; k < 2; ++k) {
          request.geometry = (k + r) % 2 == 1;
          auto result = (*pipeline)->Step(request);
          if (!result.ok()) {
            std::fprintf(stderr, "%s\n", far::ToString(result.error()).c_str());
            return 1;
          }
          if (!request.geometry) {
            plain_ms.push_back(result->stats.total_ms);
            continue;
          }
          geometry_ms.push_back(result->stats.total_ms);
          stage_ms.push_back(StageMs(*result, far::Stage::kGeometry));
          contacts = result->contacts.size();
          distance_pairs = result->distance_pairs.size();
          penetrations = result->penetrations.size();
          closed = 0;
          for (const far::Penetration& p : result->penetrations) closed += p.closed;
        }
      }
    }
    std::printf(
        "| %s | %zu | %zu | %zu (%zu) | %s | %s | %.2f | %s |\n", name.c_str(), contacts,
        distance_pairs, penetrations, closed, Spread(plain_ms).c_str(), Spread(geometry_ms).c_str(),
        far::Quantile(geometry_ms, 0.5) / far::Quantile(plain_ms, 0.5), Spread(stage_ms).c_str());
  }
  return 0;
}
