// far-daemon: the FAR collision-culling service. See README.md and docs/daemon.md.
#include <malloc.h>

#include <csignal>
#include <cstdio>

#include "daemon.h"
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "far/model/version.h"

namespace {

std::atomic<bool> g_stop{false};

void OnSignal(int) { g_stop = true; }  // async-signal-safe: a lock-free atomic store

}  // namespace

int main(int argc, char** argv) {
  using far::server::DaemonConfig;
  CLI::App app{"far-daemon: GPU collision culling (FAR) for simulators over LCM + shared memory"};
  app.set_version_flag("--version", std::string("far-daemon ") + far::kVersion);
  std::string config_path, gl_platform;
  DaemonConfig flags;
  app.add_option("--config", config_path, "JSON config file (docs/daemon.md); flags override it");
  auto* name = app.add_option("--name", flags.name,
                              "this daemon's name: its socket <dir>/<name>.sock and LCM channel "
                              "prefix; clients choose a daemon by name (far-client --daemon)")
                   ->capture_default_str();
  auto* socket =
      app.add_option("--socket", flags.socket_path,
                     "socket path (default: $FAR_SOCKET_DIR/<name>.sock when set, "
                     "else /run/far/<name>.sock when /run/far exists, else "
                     "$XDG_RUNTIME_DIR/far/<name>.sock, else /tmp/far-<uid>/<name>.sock)");
  auto* gpu = app.add_option("--gpu", flags.gpu,
                             "EGL device index of the GPU to use, as --list-gpus numbers them "
                             "(that device and no other; a second GPU gets a second daemon "
                             "with its own --name)");
  bool list_gpus = false;
  app.add_flag("--list-gpus", list_gpus, "list the EGL devices with their index, and exit");
  auto* url = app.add_option("--lcm-url", flags.lcm_url, "LCM URL")->capture_default_str();
  auto* platform =
      app.add_option("--gl-platform", gl_platform,
                     "auto (default: a GPU, else Mesa's software renderer), device (a GPU "
                     "only: fails without one) or surfaceless");
  auto* sessions =
      app.add_option("--max-sessions", flags.max_sessions, "session limit")->capture_default_str();
  auto* triangles =
      app.add_option("--max-triangles", flags.max_triangles_per_session, "triangles per session")
          ->capture_default_str();
  auto* vertices =
      app.add_option("--max-vertices", flags.max_vertices_per_session, "vertices per session")
          ->capture_default_str();
  auto* objects =
      app.add_option("--max-objects", flags.max_objects_per_session, "objects per session")
          ->capture_default_str();
  auto* max_resolution = app.add_option("--max-resolution", flags.max_resolution,
                                        "largest viewport a request may ask for")
                             ->capture_default_str();
  auto* ring = app.add_option("--ring-bytes", flags.ring_bytes,
                              "update ring bytes per session (power of two)")
                   ->capture_default_str();
  auto* rate = app.add_option("--max-rate", flags.max_requests_per_second,
                              "step requests per second per session")
                   ->capture_default_str();
  auto* per_user = app.add_option("--max-sessions-per-user", flags.max_sessions_per_user,
                                  "sessions one user may hold")
                       ->capture_default_str();
  auto* open_rate =
      app.add_option("--max-opens-per-second", flags.max_opens_per_second_per_user,
                     "sessions one user may open per second, sustained (bursts of as many)")
          ->capture_default_str();
  auto* triangles_total = app.add_option("--max-triangles-total", flags.max_triangles_total,
                                         "triangles of all sessions together")
                              ->capture_default_str();
  auto* vertices_total = app.add_option("--max-vertices-total", flags.max_vertices_total,
                                        "vertices of all sessions together")
                             ->capture_default_str();
  auto* reply_pairs = app.add_option("--max-reply-pairs", flags.max_reply_pairs,
                                     "contact and distance pairs in one reply")
                          ->capture_default_str();
  auto* deadline = app.add_option("--step-deadline-ms", flags.step_deadline_ms,
                                  "the longest a step may wait and run")
                       ->capture_default_str();
  auto* threads =
      app.add_option("--threads", flags.exact_threads, "CPU threads for exact tests (0: all)")
          ->capture_default_str();
  auto* level = app.add_option("--log-level", flags.log_level, "trace, debug, info, warn, error")
                    ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (list_gpus) {
    const std::vector<std::string> devices = far::GlContext::ListDevices();
    if (devices.empty()) std::printf("no EGL devices (the EGL device platform is not offered)\n");
    for (const std::string& device : devices) std::printf("%s\n", device.c_str());
    return 0;
  }

  // The file first, then every flag given on the command line on top of it.
  DaemonConfig config;
  if (!config_path.empty()) {
    auto loaded = far::server::LoadDaemonConfig(config_path);
    if (!loaded) {
      std::fprintf(stderr, "far-daemon: %s\n", far::ToString(loaded.error()).c_str());
      return 2;
    }
    config = *loaded;
  }
  if (*name) config.name = flags.name;
  if (*socket) config.socket_path = flags.socket_path;
  if (*gpu) config.gpu = flags.gpu;
  if (*url) config.lcm_url = flags.lcm_url;
  if (*platform) {
    if (gl_platform == "auto")
      config.gl_platform = far::GlPlatform::kAuto;
    else if (gl_platform == "device")
      config.gl_platform = far::GlPlatform::kDevice;
    else if (gl_platform == "surfaceless")
      config.gl_platform = far::GlPlatform::kSurfaceless;
    else {
      std::fprintf(stderr, "far-daemon: --gl-platform: unknown '%s'\n", gl_platform.c_str());
      return 2;
    }
  }
  if (*max_resolution) config.max_resolution = flags.max_resolution;
  if (*sessions) config.max_sessions = flags.max_sessions;
  if (*triangles) config.max_triangles_per_session = flags.max_triangles_per_session;
  if (*vertices) config.max_vertices_per_session = flags.max_vertices_per_session;
  if (*objects) config.max_objects_per_session = flags.max_objects_per_session;
  if (*ring) config.ring_bytes = flags.ring_bytes;
  if (*rate) config.max_requests_per_second = flags.max_requests_per_second;
  if (*per_user) config.max_sessions_per_user = flags.max_sessions_per_user;
  if (*open_rate) config.max_opens_per_second_per_user = flags.max_opens_per_second_per_user;
  if (*triangles_total) config.max_triangles_total = flags.max_triangles_total;
  if (*vertices_total) config.max_vertices_total = flags.max_vertices_total;
  if (*reply_pairs) config.max_reply_pairs = flags.max_reply_pairs;
  if (*deadline) config.step_deadline_ms = flags.step_deadline_ms;
  if (*threads) config.exact_threads = flags.exact_threads;
  if (*level) config.log_level = flags.log_level;
  if (auto ok = far::server::ValidateDaemonConfig(config); !ok) {
    std::fprintf(stderr, "far-daemon: %s\n", far::ToString(ok.error()).c_str());
    return 2;
  }

  // Structured logs: one line per event, key=value.
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e level=%l %v");
  spdlog::set_level(spdlog::level::from_str(config.log_level));

  // Memory goes back to the system when sessions close (malloc_trim after each, see
  // SessionRegistry::ReapWorkers). Large buffers (meshes, ring records) stay on the heap up to
  // 32 MiB for reuse rather than costing a fresh zero-filled mmap each (bench/RESULTS.md, ring
  // ingest), and few arenas keep the many worker threads from scattering it.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_ARENA_MAX, 4);

  auto daemon = far::server::Daemon::Create(config);
  if (!daemon) {
    std::fprintf(stderr, "far-daemon: %s\n", far::ToString(daemon.error()).c_str());
    return 1;
  }
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);
  if (auto ran = (*daemon)->Run(&g_stop); !ran) {
    std::fprintf(stderr, "far-daemon: %s\n", far::ToString(ran.error()).c_str());
    return 1;
  }
  return 0;
}
