// The daemon's resident memory per session against the session's triangles (issue 9: "record
// the daemon's RSS per session against triangles"), measured on a real far-daemon started here
// with its default limits and printed as a markdown table for bench/RESULTS.md. For each scene
// size and method: one session uploads far::scenes::ScalingScene of that size (ground, spheres,
// cloths), steps once (contacts), and the daemon's VmRSS, RssAnon (the session's own memory:
// mesh, world vertices, hierarchies, FCL models, llvmpipe's GL buffers) and RssShmem (the
// session's shared rings, as far as the client has written them) are read while it is open and
// after it closed.
// Run inside a network namespace (it re-runs itself through deploy/netns-run.sh otherwise):
//   deploy/netns-run.sh build/release/bench/daemon/far_memory_study
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "large_scene.h"
#include "study_daemon.h"
#include <CLI/CLI.hpp>

#include "far/model/step_request.h"

namespace far::study {
namespace {

using namespace std::chrono_literals;

struct Settings {
  std::vector<int64_t> triangles = {10'000, 30'000, 100'000, 300'000, 1'000'000, 1'990'000};
  std::vector<std::string> methods = {"bvh", "fcl", "far"};
  int64_t gl_max_triangles = 100'000;  // GL methods on llvmpipe: seconds per step beyond
  std::string daemon = FAR_DAEMON_PATH;
};

bool UsesGl(far::Method method) { return far::NeedsGl(method); }

[[noreturn]] void Die(const std::string& what, const Error& error) {
  std::fprintf(stderr, "far_memory_study: %s: %s\n", what.c_str(), far::ToString(error).c_str());
  std::exit(1);
}

// The daemon's memory, in KiB.
struct Memory {
  int64_t rss = 0, anon = 0, shmem = 0, file = 0;
};

Memory Read(const StudyDaemon& daemon) {
  return {daemon.ResidentKiB(), daemon.StatusKiB("RssAnon"), daemon.StatusKiB("RssShmem"),
          daemon.StatusKiB("RssFile")};
}

double MiB(int64_t kib) { return static_cast<double>(kib) / 1024.0; }

// One row: a session of `scene` that steps once with `method`.
void MeasureSession(const StudyDaemon& daemon, const Scene& scene, Method method) {
  daemon.SettledResidentKiB();  // the last session's memory is gone
  const Memory before = Read(daemon);
  Memory open;
  double step_ms = 0;
  {
    auto client = client::Client::Connect(daemon.Options("memory", 600s));
    if (!client) Die("open", client.error());
    if (auto ok = UploadInParts(**client, scene); !ok) Die("upload", ok.error());
    StepRequest request;
    request.method = method;
    const auto start = std::chrono::steady_clock::now();
    if (auto stepped = (*client)->Step(request); !stepped) Die("step", stepped.error());
    step_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    open = Read(daemon);
  }
  const int64_t after = daemon.SettledResidentKiB();
  const int64_t triangles = TriangleCount(scene);
  const double anon_bytes = static_cast<double>(open.anon - before.anon) * 1024.0;
  std::printf("| %lld | %lld | %s | %.0f | %.1f | %.1f | %.1f | %.1f | %.0f | %+.1f |\n",
              static_cast<long long>(triangles), static_cast<long long>(VertexCount(scene)),
              std::string(ToString(method)).c_str(), step_ms, MiB(open.rss - before.rss),
              MiB(open.anon - before.anon), MiB(open.shmem - before.shmem),
              MiB(open.file - before.file), anon_bytes / static_cast<double>(triangles),
              MiB(after - before.rss));
}

void PrintHeader(int argc, char** argv, const StudyDaemon& daemon) {
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M", std::localtime(&now));
  auto status = daemon.Status();
  std::string command;
  for (int i = 0; i < argc; ++i) command += std::string(i ? " " : "") + argv[i];
  std::printf("# far-daemon memory per session\n\n");
  std::printf("- date: %s\n- machine: %u cores (%s)\n- GL_RENDERER: %s\n- command: `%s`\n\n", date,
              std::thread::hardware_concurrency(), CpuModel().c_str(),
              status ? status->gl_renderer.c_str() : "unknown", command.c_str());
  std::printf(
      "One far-daemon with its default limits, warmed up by one small session per method; per "
      "row one session uploads ScalingScene of that size, steps once (contacts) and closes. "
      "Differences are to the daemon's settled memory "
      "before the session opened: VmRSS = RssAnon (the session's own memory) + RssShmem (its "
      "shared rings as far as written) + RssFile (mapped files); \"after close\" is the settled "
      "VmRSS after "
      "it closed.\n\n");
  std::printf(
      "| triangles | vertices | method | step ms | VmRSS open (MiB) | RssAnon (MiB) | RssShmem "
      "(MiB) | RssFile (MiB) | RssAnon bytes / triangle | after close (MiB) |\n");
  std::printf("| --: | --: | --- | --: | --: | --: | --: | --: | --: | --: |\n");
}

}  // namespace
}  // namespace far::study

int main(int argc, char** argv) {
  using namespace far::study;
  EnterNetworkNamespace(argc, argv, FAR_NETNS_RUN_PATH);
  Settings settings;
  CLI::App app{"far_memory_study: the daemon's RSS per session against triangles"};
  app.add_option("--triangles", settings.triangles, "scene sizes (ScalingScene), at most 2M")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--methods", settings.methods, "methods to step with")
      ->delimiter(',')
      ->capture_default_str()
      ->check([](const std::string& name) {
        return far::ParseMethod(name) ? "" : "unknown method (" + far::MethodNames() + ")";
      });
  app.add_option("--gl-max-triangles", settings.gl_max_triangles,
                 "largest scene for the GL methods (far, far-exact-offset, cullide)")
      ->capture_default_str();
  app.add_option("--daemon", settings.daemon, "far-daemon to start")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  auto daemon = StudyDaemon::Start(settings.daemon, {});
  if (!daemon) Die("start", daemon.error());
  // A warm-up session per method (a small scene): code pages and one-time setup (threads, the
  // GL platform) are not any row's memory.
  for (const std::string& name : settings.methods) {
    auto client = far::client::Client::Connect((*daemon)->Options("warm-up", 600s));
    if (!client) Die("warm-up", client.error());
    if (auto ok = UploadInParts(**client, LargestScene(2000)); !ok) Die("warm-up", ok.error());
    far::StepRequest request;
    request.method = *far::ParseMethod(name);
    if (auto stepped = (*client)->Step(request); !stepped) Die("warm-up", stepped.error());
  }
  PrintHeader(argc, argv, **daemon);
  for (const int64_t triangles : settings.triangles) {
    const far::Scene scene = LargestScene(triangles);
    for (const std::string& name : settings.methods) {
      const far::Method method = *far::ParseMethod(name);
      if (UsesGl(method) && triangles > settings.gl_max_triangles) continue;
      MeasureSession(**daemon, scene, method);
    }
  }
  std::printf("\n");
  return 0;
}
