// What the daemon costs over calling the pipeline in-process, per step, on the same scene.
//
// One process runs far-daemon's Daemon on a background thread (its own GL context) and a
// Pipeline on the main thread (another context), loads the same 10k-triangle scene into both
// (the daemon through a Client session), then steps them interleaved. Per daemon step the
// overhead is the client's round trip minus the pipeline time the daemon itself measured
// (stats.total_ms): LCM request, scheduling, ring drain, reply encoding and delivery. The
// in-process step time is reported beside it for scale. Run inside a network namespace:
//   deploy/netns-run.sh build/release/bench/daemon/far_daemon_overhead_study [steps]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include "daemon.h"

#include "far/base/quantile.h"
#include "far/client/client.h"
#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace {

using Clock = std::chrono::steady_clock;
using far::Quantile;

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 100;
  far::server::DaemonConfig config;
  config.log_level = "warn";
  auto daemon = far::server::Daemon::Create(config);
  if (!daemon) {
    std::fprintf(stderr, "%s\n", far::ToString(daemon.error()).c_str());
    return 1;
  }
  std::thread serving([&] { (void)(*daemon)->Run(); });

  // 40 rigid objects of 250 triangles: 10k triangles.
  auto objects = far::scenes::RandomSoup(3, 40, 250, 4.0, 0.25);
  auto pipeline = far::Pipeline::Create();
  if (!pipeline) return 1;
  far::client::ClientOptions options;
  options.timeout = std::chrono::milliseconds(20000);
  std::unique_ptr<far::client::Client> client;
  for (int attempt = 0; attempt < 50 && !client; ++attempt) {
    auto connected = far::client::Client::Connect(options);
    if (connected) client = std::move(*connected);
  }
  if (!client) return 1;
  for (const auto& o : objects) {
    (void)(*pipeline)->AddObject(o.id, o.mesh, o.motion, o.X_WO);
    (void)client->AddObject(o.id, o.mesh, o.motion, o.X_WO);
  }
  far::StepRequest request;
  request.resolution = 256;
  std::vector<double> in_process, round_trip, daemon_pipeline, overhead;
  for (int s = -3; s < steps; ++s) {  // 3 warm-up steps
    // Both scenes move the same way: every rigid object drifts.
    for (auto& o : objects) {
      o.X_WO.translation.x() += 0.001 * std::sin(0.1 * s + o.id);
      (void)(*pipeline)->SetPose(o.id, o.X_WO);
      (void)client->SetPose(o.id, o.X_WO);
    }
    auto local = (*pipeline)->Step(request);
    const auto t0 = Clock::now();
    auto remote = client->Step(request);
    const double rt = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!local || !remote) {
      std::fprintf(stderr, "step failed: %s\n",
                   far::ToString(local ? remote.error() : local.error()).c_str());
      return 1;
    }
    if (remote->contacts != local->contacts) std::fprintf(stderr, "step %d: contacts differ!\n", s);
    if (s < 0) continue;
    in_process.push_back(local->stats.total_ms);
    round_trip.push_back(rt);
    daemon_pipeline.push_back(remote->stats.total_ms);
    overhead.push_back(rt - remote->stats.total_ms);
  }
  std::printf(
      "scene: %zu objects, 10000 triangles, method far, id-buffer, 256x256, %d steps, GL_RENDERER "
      "%s\n",
      objects.size(), steps, (*pipeline)->gl_renderer().c_str());
  std::printf("| measure | median ms | p99 ms |\n| --- | ---: | ---: |\n");
  std::printf("| in-process Pipeline::Step | %.3f | %.3f |\n", Quantile(in_process, 0.5),
              Quantile(in_process, 0.99));
  std::printf("| daemon: client round trip | %.3f | %.3f |\n", Quantile(round_trip, 0.5),
              Quantile(round_trip, 0.99));
  std::printf("| daemon: pipeline inside the daemon | %.3f | %.3f |\n",
              Quantile(daemon_pipeline, 0.5), Quantile(daemon_pipeline, 0.99));
  std::printf("| **daemon overhead** (round trip - pipeline) | **%.3f** | **%.3f** |\n",
              Quantile(overhead, 0.5), Quantile(overhead, 0.99));
  client.reset();
  (*daemon)->Stop();
  serving.join();
  return 0;
}
