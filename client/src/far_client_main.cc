// far-client: probe a running far-daemon, run scene files through it, and load-test it.
// Usage and examples: far-client --help, far-client <command> --help, README.md.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "far/client/client.h"
#include "far/io/mesh_io.h"
#include "far/io/scene_io.h"
#include "far/model/quantile.h"
#include "far/scenes/scenes.h"

namespace {

using far::Quantile;
using far::client::Client;
using far::client::ClientOptions;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

int Fail(const far::Error& error) {
  std::fprintf(stderr, "far-client: %s\n", far::ToString(error).c_str());
  return 1;
}

// Options shared by the commands that run steps.
struct StepFlags {
  std::string method = "auto", mechanism = "id-buffer", output, depth = "depth24";
  int resolution = 1024, subobject_size = 1;
  double distance = 0;
  CLI::Option* distance_option = nullptr;

  void Add(CLI::App* command) {
    command
        ->add_option("--method", method,
                     "auto (the fastest reliable method for the daemon's renderer and the scene), "
                     "bvh, aabb, far, far-exact-offset, cullide (not reliable), fcl or exact")
        ->capture_default_str();
    command->add_option("--mechanism", mechanism, "GPU methods: id-buffer or occlusion-query")
        ->capture_default_str();
    command
        ->add_option("--resolution", resolution,
                     "viewport size (8..8192; the daemon refuses more than its max_resolution, "
                     "default 4096)")
        ->capture_default_str();
    command->add_option("--depth-format", depth, "depth16, depth24 or depth32f")
        ->capture_default_str();
    command->add_option("--subobject-size", subobject_size, "triangles per sub-object")
        ->capture_default_str();
    distance_option = command->add_option(
        "--distance", distance, "distance D >= 0: report every triangle pair closer than D");
    command->add_option(
        "--output", output,
        "deepest output: object-pcs (objects only), pairs (object pairs), pcs (object and "
        "primitive PCS), contacts, "
        "distance (default: contacts, or distance when --distance is given)");
  }

  far::Result<far::StepRequest> Request() const {
    far::StepRequest request;
    auto m = far::ParseMethod(method);
    if (!m)
      return far::MakeError(far::ErrorCode::kInvalidArgument, "--method: unknown '" + method + "'");
    auto k = far::ParseMechanism(mechanism);
    if (!k)
      return far::MakeError(far::ErrorCode::kInvalidArgument,
                            "--mechanism: unknown '" + mechanism + "'");
    auto d = far::ParseDepthFormat(depth);
    if (!d)
      return far::MakeError(far::ErrorCode::kInvalidArgument,
                            "--depth-format: unknown '" + depth + "'");
    request.method = *m;
    request.mechanism = *k;
    request.depth_format = *d;
    request.resolution = resolution;
    request.subobject_size = subobject_size;
    const bool has_distance = distance_option->count() > 0;
    if (has_distance) {
      if (!std::isfinite(distance) || distance < 0) {
        return far::MakeError(far::ErrorCode::kInvalidArgument,
                              "--distance: " + std::to_string(distance) +
                                  " is not a finite number >= 0");
      }
      request.distance = distance;
    }
    std::string out = output.empty() ? (has_distance ? "distance" : "contacts") : output;
    auto o = far::ParseOutput(out);
    if (!o)
      return far::MakeError(far::ErrorCode::kInvalidArgument, "--output: unknown '" + out + "'");
    request.output = *o;
    return request;
  }
};

json StatsJson(const far::StepStats& stats) {
  json stages = json::object();
  for (const auto& stage : stats.stages) stages[stage.name] = stage.ms;
  return {{"method", stats.method},
          {"method_reason", stats.method_reason},
          {"total_ms", stats.total_ms},
          {"stages_ms", stages},
          {"primitives_rendered", stats.primitives_rendered},
          {"draws", stats.draws},
          {"queries", stats.queries},
          {"bytes_uploaded", stats.bytes_uploaded},
          {"object_pairs", stats.object_pairs},
          {"pairs_considered", stats.pairs_considered},
          {"pairs_tested", stats.pairs_tested},
          {"object_radius", stats.object_radius},
          {"primitive_radius", stats.primitive_radius}};
}

json ResultJson(const far::StepResult& result) {
  json contacts = json::array(), distance_pairs = json::array(), pcs_primitives = json::object();
  for (const auto& c : result.contacts)
    contacts.push_back({c.object_a, c.triangle_a, c.object_b, c.triangle_b});
  for (const auto& d : result.distance_pairs) {
    distance_pairs.push_back(
        {d.pair.object_a, d.pair.triangle_a, d.pair.object_b, d.pair.triangle_b, d.distance});
  }
  for (const auto& [id, triangles] : result.pcs_primitives)
    pcs_primitives[std::to_string(id)] = triangles;
  json pairs = json::array();
  for (const auto& p : result.object_pairs) pairs.push_back({p.object_a, p.object_b});
  return {{"contacts", contacts},
          {"distance_pairs", distance_pairs},
          {"pcs_objects", result.pcs_objects},
          {"pcs_primitives", pcs_primitives},
          {"object_pairs", pairs},
          {"stats", StatsJson(result.stats)}};
}

int Status(const std::string& url, int timeout_ms, bool as_json) {
  auto status = Client::Status(url, std::chrono::milliseconds(timeout_ms));
  if (!status) return Fail(status.error());
  if (as_json) {
    json sessions = json::array();
    for (const auto& s : status->sessions) {
      sessions.push_back({{"id", s.id},
                          {"client", s.client_name},
                          {"steps", s.steps},
                          {"objects", s.objects},
                          {"latency_p50_ms", s.latency_p50_ms},
                          {"latency_p99_ms", s.latency_p99_ms}});
    }
    json errors = json::object();
    for (const auto& [kind, count] : status->errors_by_kind) errors[kind] = count;
    std::cout << json{{"daemon_version", status->daemon_version},
                      {"gl_renderer", status->gl_renderer},
                      {"uptime_ms", status->uptime_ms},
                      {"steps_total", status->steps_total},
                      {"errors_total", status->errors_total},
                      {"errors_by_kind", errors},
                      {"rejected_messages_total", status->rejected_messages_total},
                      {"max_sessions", status->max_sessions},
                      {"latency_ms",
                       {{"p50", status->latency_p50_ms},
                        {"p90", status->latency_p90_ms},
                        {"p99", status->latency_p99_ms},
                        {"max", status->latency_max_ms},
                        {"samples", status->latency_samples}}},
                      {"sessions", sessions}}
                     .dump(2)
              << "\n";
    return 0;
  }
  std::printf("far-daemon %s, up %.1f s\nGL_RENDERER: %s\n", status->daemon_version.c_str(),
              status->uptime_ms / 1000.0, status->gl_renderer.c_str());
  std::printf("steps: %lld  errors: %lld  rejected messages: %lld\n",
              static_cast<long long>(status->steps_total),
              static_cast<long long>(status->errors_total),
              static_cast<long long>(status->rejected_messages_total));
  std::printf("step latency ms: p50 %.3f  p90 %.3f  p99 %.3f  max %.3f  (%lld steps)\n",
              status->latency_p50_ms, status->latency_p90_ms, status->latency_p99_ms,
              status->latency_max_ms, static_cast<long long>(status->latency_samples));
  for (const auto& [kind, count] : status->errors_by_kind) {
    std::printf("errors %-20s %lld\n", kind.c_str(), static_cast<long long>(count));
  }
  std::printf("sessions: %zu of %d\n", status->sessions.size(), status->max_sessions);
  for (const auto& s : status->sessions) {
    std::printf("  session %lld  %-16s steps %-8lld objects %-6d p50 %.3f ms  p99 %.3f ms\n",
                static_cast<long long>(s.id), s.client_name.c_str(),
                static_cast<long long>(s.steps), s.objects, s.latency_p50_ms, s.latency_p99_ms);
  }
  return 0;
}

// Per-client results of a load run.
struct LoadStats {
  std::vector<double> latency_ms;
  int errors = 0;
  std::string first_error;
};

int Load(const ClientOptions& base, int clients, int steps, double seconds,
         const std::string& scene_path, const far::StepRequest& request, bool as_json) {
  far::Scene scene;
  if (!scene_path.empty()) {
    auto loaded = far::ReadScene(scene_path);
    if (!loaded) return Fail(loaded.error());
    scene = std::move(*loaded);
  }
  std::vector<LoadStats> stats(static_cast<size_t>(clients));
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  const auto deadline_of = [&](Clock::time_point start) {
    return seconds > 0 ? start + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(seconds))
                       : Clock::time_point::max();
  };
  Clock::time_point start;
  std::vector<std::thread> threads;
  for (int i = 0; i < clients; ++i) {
    threads.emplace_back([&, i] {
      LoadStats& mine = stats[static_cast<size_t>(i)];
      ClientOptions options = base;
      options.client_name = "load-" + std::to_string(i);
      auto client = Client::Connect(options);
      auto fail = [&](const far::Error& e) {
        if (mine.errors++ == 0) mine.first_error = far::ToString(e);
      };
      if (!client) {
        fail(client.error());
        ready++;
        return;
      }
      // Each client simulates its own scene: the given one, or a random soup of rigid objects.
      std::vector<far::SceneObject> objects =
          scene_path.empty() ? far::scenes::RandomSoup(static_cast<uint64_t>(i), 24, 40, 3.0, 0.4)
                             : scene.objects;
      for (const auto& o : objects) {
        if (auto ok = (*client)->AddObject(o.id, o.mesh, o.motion, o.X_WO); !ok) fail(ok.error());
      }
      ready++;
      // Everyone starts together, once the main thread has set `start` and said go.
      while (!go) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const auto deadline = deadline_of(start);
      for (int s = 0; (steps <= 0 || s < steps) && Clock::now() < deadline; ++s) {
        // Rigid objects drift a little every step, as a simulation would move them.
        for (auto& o : objects) {
          if (o.motion != far::Motion::kRigid) continue;
          o.X_WO.translation.x() += 0.002 * std::sin(0.1 * s + o.id);
          if (auto ok = (*client)->SetPose(o.id, o.X_WO); !ok) fail(ok.error());
        }
        const auto t0 = Clock::now();
        auto result = (*client)->Step(request);
        if (!result) {
          fail(result.error());
          continue;
        }
        mine.latency_ms.push_back(
            std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      }
    });
  }
  while (ready < clients) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  start = Clock::now();
  go = true;  // (release: the workers read `start` after seeing it)
  for (auto& t : threads) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();

  std::vector<double> all;
  int errors = 0;
  size_t min_steps = SIZE_MAX, max_steps = 0;
  json per_client = json::array();
  for (int i = 0; i < clients; ++i) {
    const LoadStats& s = stats[static_cast<size_t>(i)];
    all.insert(all.end(), s.latency_ms.begin(), s.latency_ms.end());
    errors += s.errors;
    min_steps = std::min(min_steps, s.latency_ms.size());
    max_steps = std::max(max_steps, s.latency_ms.size());
    per_client.push_back({{"client", i},
                          {"steps", s.latency_ms.size()},
                          {"steps_per_s", s.latency_ms.size() / elapsed},
                          {"p50_ms", Quantile(s.latency_ms, 0.5)},
                          {"p90_ms", Quantile(s.latency_ms, 0.9)},
                          {"p99_ms", Quantile(s.latency_ms, 0.99)},
                          {"errors", s.errors},
                          {"first_error", s.first_error}});
  }
  const double fairness =
      min_steps > 0 ? static_cast<double>(max_steps) / static_cast<double>(min_steps) : 0.0;
  json overall = {{"clients", clients},
                  {"seconds", elapsed},
                  {"steps", all.size()},
                  {"steps_per_s", all.size() / elapsed},
                  {"p50_ms", Quantile(all, 0.5)},
                  {"p90_ms", Quantile(all, 0.9)},
                  {"p99_ms", Quantile(all, 0.99)},
                  {"max_ms", Quantile(all, 1.0)},
                  {"errors", errors},
                  {"fairness_max_over_min_steps", fairness}};
  if (as_json) {
    std::cout << json{{"overall", overall}, {"per_client", per_client}}.dump(2) << "\n";
  } else {
    std::printf("%-8s %8s %10s %9s %9s %9s %7s\n", "client", "steps", "steps/s", "p50 ms", "p90 ms",
                "p99 ms", "errors");
    for (const auto& c : per_client) {
      std::printf("%-8d %8zu %10.1f %9.3f %9.3f %9.3f %7d\n", c["client"].get<int>(),
                  c["steps"].get<size_t>(), c["steps_per_s"].get<double>(),
                  c["p50_ms"].get<double>(), c["p90_ms"].get<double>(), c["p99_ms"].get<double>(),
                  c["errors"].get<int>());
      if (!c["first_error"].get<std::string>().empty()) {
        std::printf("         first error: %s\n", c["first_error"].get<std::string>().c_str());
      }
    }
    std::printf(
        "overall: %zu steps in %.2f s = %.1f steps/s; latency p50 %.3f p90 %.3f p99 %.3f max %.3f "
        "ms; "
        "errors %d; fairness (max/min steps per client) %.2f\n",
        all.size(), elapsed, all.size() / elapsed, Quantile(all, 0.5), Quantile(all, 0.9),
        Quantile(all, 0.99), Quantile(all, 1.0), errors, fairness);
  }
  return errors == 0 ? 0 : 1;
}

// make-scene: one of far::scenes' generated scenes, written as far-scene/1 with its meshes.
struct MakeSceneFlags {
  std::string out, kind = "demo", mesh;
  int frames = 30, leaves = 0, cells = 0, triangles = 100000, subdivision = 5;
  uint64_t seed = 7;
  CLI::App* command = nullptr;

  CLI::App* Add(CLI::App* app) {
    command = app->add_subcommand(
        "make-scene",
        "Write a generated animated scene (far-scene/1 with frames; meshes next to it). Kinds:\n"
        "  demo      a static tree, falling deformable leaves and a vase that breaks (small)\n"
        "  leaves    the paper's falling leaves: a static tree and 150 deformable leaves that "
        "hang,\n            sway, fall and bend (vertices every frame); 42,304 triangles\n"
        "  breaking  a 100K-triangle static terrain and a 35K-triangle rigid vase that rolls "
        "into a rock\n            and breaks into 12 fragments mid-run (removal and "
        "additions, then poses)\n"
        "  bunnies   two Stanford bunnies refined to 91,850 triangles each (--subdivision 5), "
        "one static,\n            one moving rigidly through it (poses)\n"
        "  scaling   spheres (rigid), cloths (deformable) and ground (static) totalling "
        "--triangles,\n            the same mix at every size (5K to 300K), for time-vs-size "
        "curves");
    command->add_option("out", out, "scene JSON path to write (meshes go next to it)")->required();
    command->add_option("--kind", kind, "demo, leaves, breaking, bunnies or scaling")
        ->check(CLI::IsMember({"demo", "leaves", "breaking", "bunnies", "scaling"}))
        ->capture_default_str();
    command->add_option("--frames", frames, "animation frames, frame 0 included")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    command->add_option("--seed", seed, "random seed (same seed, same scene)")
        ->capture_default_str();
    command->add_option("--leaves", leaves, "demo, leaves: number of leaves (default 40, 150)")
        ->check(CLI::Range(0, 100000));
    command
        ->add_option("--cells", cells,
                     "demo, leaves: leaf grid cells per side, 2 cells^2 triangles (default 2, 8)")
        ->check(CLI::Range(1, 1000));
    command->add_option("--triangles", triangles, "scaling: target total triangles")
        ->check(CLI::Range(1000, 50000000))
        ->capture_default_str();
    command->add_option("--mesh", mesh,
                        "bunnies: the bunny mesh (default: share/far/data/bunny.obj next to "
                        "far-client's bin/, then the source tree's bench/data/bunny.obj)");
    command
        ->add_option("--subdivision", subdivision,
                     "bunnies: split each edge in n (n^2 triangles per triangle)")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    return command;
  }
};

// The bunny for `make-scene --kind bunnies`: --mesh, else the installed copy, else the source
// tree's (a build that was never installed).
far::Result<far::Mesh> ReadBunny(const std::string& mesh) {
  if (!mesh.empty()) return far::ReadMesh(mesh);
  std::vector<std::filesystem::path> tried;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) tried.push_back(exe.parent_path() / ".." / "share" / "far" / "data" / "bunny.obj");
  tried.emplace_back(FAR_SOURCE_BUNNY_OBJ);
  std::string places;
  for (const std::filesystem::path& path : tried) {
    if (std::filesystem::exists(path, ec)) return far::ReadMesh(path.lexically_normal());
    places += (places.empty() ? "" : ", ") + path.lexically_normal().string();
  }
  return far::MakeError(far::ErrorCode::kNotFound,
                        "no bunny mesh: tried " + places + "; pass one with --mesh PATH");
}

int MakeScene(const MakeSceneFlags& flags) {
  const auto given = [&](const char* option) { return flags.command->count(option) > 0; };
  const bool leaf_kind = flags.kind == "demo" || flags.kind == "leaves";
  for (const char* option : {"--leaves", "--cells"}) {
    if (!leaf_kind && given(option)) {
      std::fprintf(stderr, "far-client: %s applies to --kind demo or leaves only\n", option);
      return 1;
    }
  }
  const auto t0 = Clock::now();
  far::Scene scene;
  if (flags.kind == "demo") {
    scene = far::scenes::AnimatedLeavesScene(flags.seed, given("--leaves") ? flags.leaves : 40,
                                             given("--cells") ? flags.cells : 2, flags.frames);
  } else if (flags.kind == "leaves") {
    scene = far::scenes::PaperLeavesScene(flags.seed, flags.frames,
                                          given("--leaves") ? flags.leaves : 150,
                                          given("--cells") ? flags.cells : 8);
  } else if (flags.kind == "breaking") {
    scene = far::scenes::BreakingScene(flags.seed, flags.frames);
  } else if (flags.kind == "bunnies") {
    auto bunny = ReadBunny(flags.mesh);
    if (!bunny) return Fail(bunny.error());
    scene = far::scenes::BunniesScene(*bunny, flags.subdivision, flags.seed, flags.frames);
  } else {
    scene = far::scenes::ScalingScene(flags.seed, flags.triangles, flags.frames);
  }
  const double generated_s = std::chrono::duration<double>(Clock::now() - t0).count();
  int64_t triangles = 0;
  for (const far::SceneObject& object : scene.objects) triangles += object.mesh.num_triangles();
  std::filesystem::create_directories(std::filesystem::absolute(flags.out).parent_path());
  if (auto ok = far::WriteScene(scene, flags.out); !ok) return Fail(ok.error());
  std::printf(
      "wrote %s (%s): %zu objects and %lld triangles at frame 0, %zu frames (%zu "
      "updates); generated in %.2f s\n",
      flags.out.c_str(), flags.kind.c_str(), scene.objects.size(),
      static_cast<long long>(triangles), scene.frames.size() + 1, scene.frames.size(), generated_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"far-client: probe a far-daemon, run scene files through it, load-test it"};
  app.require_subcommand(1);
  app.fallthrough();  // --lcm-url and --timeout-ms may also come after the command
  ClientOptions options;
  int timeout_ms = 5000;
  app.add_option("--lcm-url", options.lcm_url, "LCM URL of the daemon")->capture_default_str();
  app.add_option("--timeout-ms", timeout_ms, "wait this long for the daemon's replies")
      ->capture_default_str();
  bool as_json = false;

  auto* ping =
      app.add_subcommand("ping", "Check that a daemon answers; prints the round-trip time");
  auto* status = app.add_subcommand("status",
                                    "Print the daemon's status: GL renderer, sessions, steps, "
                                    "latency percentiles, errors by kind");
  status->add_flag("--json", as_json, "print JSON");

  std::string scene_path;
  StepFlags collide_flags;
  auto* collide =
      app.add_subcommand("collide",
                         "Upload a scene through the ring, run one step, print JSON:\n"
                         "  {contacts: [[objA, triA, objB, triB], ...], distance_pairs: "
                         "[[objA, triA, objB, triB, d], ...],\n   pcs_objects, pcs_primitives: "
                         "{objId: [tri, ...]}, object_pairs, stats}");
  collide->add_option("scene", scene_path, "far-scene/1 JSON file (docs/scene-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  collide_flags.Add(collide);

  int play_steps = 0;
  StepFlags play_flags;
  auto* play = app.add_subcommand(
      "play", "Run an animated scene (its frames) step by step; one stats line per step");
  play->add_option("scene", scene_path, "far-scene/1 JSON file with frames")
      ->required()
      ->check(CLI::ExistingFile);
  play->add_option("--steps", play_steps, "steps to run (default: 1 + number of frames)");
  play->add_flag("--json", as_json, "print one JSON object per step");
  play_flags.Add(play);

  int clients = 4, load_steps = 100;
  double load_seconds = 0;
  StepFlags load_flags;
  std::string load_scene;
  auto* load =
      app.add_subcommand("load",
                         "Run N concurrent clients, each with its own session and scene; "
                         "prints throughput and latency percentiles per client and overall");
  load->add_option("--clients", clients, "concurrent clients (threads)")->capture_default_str();
  load->add_option("--steps", load_steps, "steps per client (0: until --seconds)")
      ->capture_default_str();
  load->add_option("--seconds", load_seconds, "stop after this many seconds");
  load->add_option("--scene", load_scene,
                   "scene each client uploads (default: a random soup per client)");
  load->add_flag("--json", as_json, "print JSON");
  load_flags.Add(load);

  MakeSceneFlags make_scene_flags;
  auto* make_scene = make_scene_flags.Add(&app);
  CLI11_PARSE(app, argc, argv);
  options.timeout = std::chrono::milliseconds(timeout_ms);

  if (*ping) {
    const auto t0 = Clock::now();
    auto answered = Client::Status(options.lcm_url, options.timeout);
    if (!answered) return Fail(answered.error());
    std::printf("far-daemon answered on %s in %.3f ms (GL_RENDERER: %s)\n", options.lcm_url.c_str(),
                std::chrono::duration<double, std::milli>(Clock::now() - t0).count(),
                answered->gl_renderer.c_str());
    return 0;
  }
  if (*status) return Status(options.lcm_url, timeout_ms, as_json);
  if (*make_scene) return MakeScene(make_scene_flags);
  if (*load) {
    auto request = load_flags.Request();
    if (!request) return Fail(request.error());
    return Load(options, clients, load_steps, load_seconds, load_scene, *request, as_json);
  }

  // collide and play: one session, one scene.
  StepFlags& flags = *collide ? collide_flags : play_flags;
  auto request = flags.Request();
  if (!request) return Fail(request.error());
  auto scene = far::ReadScene(scene_path);
  if (!scene) return Fail(scene.error());
  options.client_name = *collide ? "far-client collide" : "far-client play";
  auto client = Client::Connect(options);
  if (!client) return Fail(client.error());
  if (auto ok = (*client)->LoadScene(*scene); !ok) return Fail(ok.error());
  if (*collide) {
    auto result = (*client)->Step(*request);
    if (!result) return Fail(result.error());
    std::cout << ResultJson(*result).dump() << "\n";
    return 0;
  }
  const int total = play_steps > 0 ? play_steps : static_cast<int>(scene->frames.size()) + 1;
  for (int step = 0; step < total; ++step) {
    // Step 0 is the scene as loaded; frame k is applied before step k + 1.
    if (step > 0 && static_cast<size_t>(step - 1) < scene->frames.size()) {
      if (auto ok = (*client)->ApplyFrame(scene->frames[static_cast<size_t>(step - 1)]); !ok)
        return Fail(ok.error());
    }
    const auto t0 = Clock::now();
    auto result = (*client)->Step(*request);
    if (!result) return Fail(result.error());
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (as_json) {
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
