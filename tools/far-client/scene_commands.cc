// far-client collide and play: one session runs a scene file, one step or frame by frame.
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "object_listing.h"
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
  bool contacts = false;     // play: list each step's contacts by object pair
  bool certificate = false;  // play: print every step's certificate, not only on a change
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
  std::cout << ResultJson(*result, request->geometry).dump() << "\n";
  return 0;
}

// One JSON object per step; `objects` (when given) adds the contacts grouped by object pair.
void PrintStepJson(int step, double ms, const StepResult& result, const FrameUpdate* frame,
                   const SceneObjects* objects) {
  json line = {{"step", step},
               {"round_trip_ms", ms},
               {"pcs_objects", result.pcs_objects.size()},
               {"contacts", result.contacts.size()},
               {"distance_pairs", result.distance_pairs.size()},
               {"removed", json::array()},
               {"added", json::array()},
               {"stats", StatsJson(result.stats)}};
  if (frame != nullptr) {
    line["removed"] = frame->removals;
    for (const SceneObject& object : frame->additions) line["added"].push_back(object.id);
  }
  if (objects != nullptr) {
    line["object_contacts"] = json::array();
    for (const ObjectContact& contact : GroupByObjectPair(result.contacts, *objects))
      line["object_contacts"].push_back(ToJson(contact, *objects));
  }
  std::cout << line.dump() << "\n";
}

void PrintStepLine(int step, double ms, const StepResult& result) {
  size_t pcs_triangles = 0;
  for (const auto& [id, tris] : result.pcs_primitives) pcs_triangles += tris.size();
  std::printf(
      "step %3d  round trip %8.2f ms  pipeline %8.2f ms  pcs objects %4zu  pcs triangles %6zu  "
      "object pairs %4lld  contacts %5zu  distance pairs %5zu  method %s\n",
      step, ms, result.stats.total_ms, result.pcs_objects.size(), pcs_triangles,
      static_cast<long long>(result.stats.object_pairs), result.contacts.size(),
      result.distance_pairs.size(), result.stats.method.c_str());
}

// What play's text output remembers from step to step, so that the certificate and auto's
// reason are printed when they change.
struct PlayTextState {
  std::string configuration;  // the method that answered the last step
  bool calibrating = false;   // auto was trying candidates
};

// One step as text: the frame's removals and additions, the stats line (ending with the method
// that answered), the contacts by object pair (--contacts), then why auto chose the method and
// the certificate, when they change (every step with --certificate).
void PrintStepText(int step, double ms, const StepResult& result,
                   const std::vector<std::string>& events, const SceneFlags& flags,
                   const SceneObjects& objects, PlayTextState& shown) {
  for (const std::string& event : events) std::printf("frame %3d: %s\n", step, event.c_str());
  PrintStepLine(step, ms, result);
  if (flags.contacts) {
    for (const ObjectContact& contact : GroupByObjectPair(result.contacts, objects))
      std::printf("      %s\n", Describe(contact, objects).c_str());
  }
  const StepStats& stats = result.stats;
  const bool changed = stats.method != shown.configuration;
  // auto's reason also when its calibration ends: "auto: calibrating: trying bvh" gives way to
  // "auto: bvh is the fastest measured (...)" with the same method.
  const bool calibrating = stats.method_reason.starts_with("auto: calibrating");
  if (!stats.method_reason.empty() &&
      (flags.certificate || changed || calibrating != shown.calibrating)) {
    std::printf("%s\n", stats.method_reason.c_str());
  }
  // The certificate depends on the configuration and the scene's extent.
  if (flags.certificate || changed) std::printf("%s", CertificateText(stats.certificate).c_str());
  shown = {stats.method, calibrating};
}

int RunPlay(const GlobalFlags& global, const SceneFlags& flags) {
  auto request = flags.step.Request();
  if (!request) return Fail(request.error());
  auto session = OpenWithScene(global, flags, "far-client play");
  if (!session) return Fail(session.error());
  const Scene& scene = session->first;
  client::Client& client = *session->second;
  const int total = flags.steps > 0 ? flags.steps : static_cast<int>(scene.frames.size()) + 1;
  SceneObjects objects(scene.objects);
  PlayTextState shown;
  for (int step = 0; step < total; ++step) {
    // Step 0 is the scene as loaded; frame k is applied before step k + 1.
    const FrameUpdate* frame = step > 0 && static_cast<size_t>(step - 1) < scene.frames.size()
                                   ? &scene.frames[static_cast<size_t>(step - 1)]
                                   : nullptr;
    std::vector<std::string> events;
    if (frame != nullptr) {
      events = DescribeRemovalsAndAdditions(*frame, objects);
      objects.Apply(*frame);
      if (auto ok = client.ApplyFrame(*frame); !ok) return Fail(ok.error());
    }
    const auto t0 = Clock::now();
    auto result = client.Step(*request, ProgressLine("step " + std::to_string(step)));
    EndProgress();
    if (!result) return Fail(result.error());
    const double ms = MsSince(t0);
    if (flags.as_json) {
      PrintStepJson(step, ms, *result, frame, flags.contacts ? &objects : nullptr);
    } else {
      PrintStepText(step, ms, *result, events, flags, objects, shown);
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
                         "{objId: [tri, ...]}, object_pairs, stats}\n"
                         "  with --geometry also contact_geometry, closest_points, "
                         "penetrations (docs/contact-geometry.md)");
  command.app->add_option("scene", flags->scene, "far-scene/1 JSON file (docs/scene-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  flags->step.Add(command.app);
  flags->step.AddTimeout(command.app);
  command.run = [&global, flags] { return RunCollide(global, *flags); };
  return command;
}

Command AddPlayCommand(CLI::App& app, const GlobalFlags& global) {
  auto flags = std::make_shared<SceneFlags>();
  Command command;
  command.app = app.add_subcommand(
      "play",
      "Run an animated scene (its frames) step by step; one stats line per step. Step 0 is the\n"
      "scene as loaded, step k follows frames[k-1]; a frame that removes or adds objects gets a\n"
      "line first: 'frame   6: vase breaks into 4 fragments: vase-fragment-1, ...'");
  command.app->add_option("scene", flags->scene, "far-scene/1 JSON file with frames")
      ->required()
      ->check(CLI::ExistingFile);
  command.app->add_option("--steps", flags->steps, "steps to run (default: 1 + number of frames)");
  command.app->add_flag("--json", flags->as_json,
                        "print one JSON object per step (with the ids 'removed' and 'added' by "
                        "the frame before it)");
  command.app->add_flag("--contacts", flags->contacts,
                        "after each step, its contacts by object pair, named as in the scene: "
                        "'leaf-12 touches tree (37 triangle pairs)' (JSON: 'object_contacts')");
  command.app->add_flag("--certificate", flags->certificate,
                        "print each step's certificate (why nothing was missed: the method's "
                        "guarantee and each GPU level's offset radius, pixel size, depth step, "
                        "rounding bound and world bounds); by default only when the "
                        "configuration changes. JSON lines always carry it in stats");
  flags->step.Add(command.app);
  flags->step.AddTimeout(command.app);
  command.run = [&global, flags] { return RunPlay(global, *flags); };
  return command;
}

}  // namespace far::cli
