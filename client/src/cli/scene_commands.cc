// far-client collide and play: one session runs a scene file, one step or frame by frame.
#include <iostream>

#include "cli_common.h"
#include "progress.h"
#include "result_json.h"
#include "step_flags.h"
#include <nlohmann/json.hpp>

#include "far/io/scene_io.h"

namespace far::cli {
namespace {

using nlohmann::json;

struct SceneFlags {
  std::string scene;
  int steps = 0;  // play: 0 = 1 + number of frames
  bool as_json = false;
  StepFlags step;
};

// Reads the scene, opens a session named `client_name` and uploads the scene.
Result<std::pair<Scene, std::unique_ptr<client::Client>>> OpenWithScene(
    const GlobalFlags& global, const SceneFlags& flags, const std::string& client_name) {
  auto scene = ReadScene(flags.scene);
  if (!scene) return scene.error();
  auto base = global.Options();
  if (!base) return base.error();
  auto options = flags.step.Options(*base);
  if (!options) return options.error();
  options->client_name = client_name;
  auto client = client::Client::Connect(*options);
  if (!client) return client.error();
  if (auto ok = (*client)->LoadScene(*scene); !ok) return ok.error();
  return std::pair{std::move(*scene), std::move(*client)};
}

int RunCollide(const GlobalFlags& global, const SceneFlags& flags) {
  auto request = flags.step.Request();
  if (!request) return Fail(request.error());
  auto session = OpenWithScene(global, flags, "far-client collide");
  if (!session) return Fail(session.error());
  auto result = session->second->Step(*request, ProgressLine("step 0"));
  EndProgress();
  if (!result) return Fail(result.error());
  std::cout << ResultJson(*result).dump() << "\n";
  return 0;
}

int RunPlay(const GlobalFlags& global, const SceneFlags& flags) {
  auto request = flags.step.Request();
  if (!request) return Fail(request.error());
  auto session = OpenWithScene(global, flags, "far-client play");
  if (!session) return Fail(session.error());
  const Scene& scene = session->first;
  client::Client& client = *session->second;
  const int total = flags.steps > 0 ? flags.steps : static_cast<int>(scene.frames.size()) + 1;
  for (int step = 0; step < total; ++step) {
    // Step 0 is the scene as loaded; frame k is applied before step k + 1.
    if (step > 0 && static_cast<size_t>(step - 1) < scene.frames.size()) {
      if (auto ok = client.ApplyFrame(scene.frames[static_cast<size_t>(step - 1)]); !ok)
        return Fail(ok.error());
    }
    const auto t0 = Clock::now();
    auto result = client.Step(*request, ProgressLine("step " + std::to_string(step)));
    EndProgress();
    if (!result) return Fail(result.error());
    const double ms = MsSince(t0);
    if (flags.as_json) {
      json line = {{"step", step},
                   {"round_trip_ms", ms},
                   {"pcs_objects", result->pcs_objects.size()},
                   {"contacts", result->contacts.size()},
                   {"distance_pairs", result->distance_pairs.size()},
                   {"stats", StatsJson(result->stats)}};
      std::cout << line.dump() << "\n";
    } else {
      size_t pcs_triangles = 0;
      for (const auto& [id, tris] : result->pcs_primitives) pcs_triangles += tris.size();
      std::printf(
          "step %3d  round trip %8.2f ms  pipeline %8.2f ms  pcs objects %4zu  pcs triangles %6zu  "
          "object pairs %4lld  contacts %5zu  distance pairs %5zu\n",
          step, ms, result->stats.total_ms, result->pcs_objects.size(), pcs_triangles,
          static_cast<long long>(result->stats.object_pairs), result->contacts.size(),
          result->distance_pairs.size());
    }
  }
  return 0;
}

}  // namespace

Command AddCollideCommand(CLI::App& app, const GlobalFlags& global) {
  auto flags = std::make_shared<SceneFlags>();
  Command command;
  command.app =
      app.add_subcommand("collide",
                         "Upload a scene through the ring, run one step, print JSON:\n"
                         "  {contacts: [[objA, triA, objB, triB], ...], distance_pairs: "
                         "[[objA, triA, objB, triB, d], ...],\n   pcs_objects, pcs_primitives: "
                         "{objId: [tri, ...]}, object_pairs, stats}");
  command.app->add_option("scene", flags->scene, "far-scene/1 JSON file (docs/scene-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  flags->step.Add(command.app);
  command.run = [&global, flags] { return RunCollide(global, *flags); };
  return command;
}

Command AddPlayCommand(CLI::App& app, const GlobalFlags& global) {
  auto flags = std::make_shared<SceneFlags>();
  Command command;
  command.app = app.add_subcommand(
      "play", "Run an animated scene (its frames) step by step; one stats line per step");
  command.app->add_option("scene", flags->scene, "far-scene/1 JSON file with frames")
      ->required()
      ->check(CLI::ExistingFile);
  command.app->add_option("--steps", flags->steps, "steps to run (default: 1 + number of frames)");
  command.app->add_flag("--json", flags->as_json, "print one JSON object per step");
  flags->step.Add(command.app);
  command.run = [&global, flags] { return RunPlay(global, *flags); };
  return command;
}

}  // namespace far::cli
