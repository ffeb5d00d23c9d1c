// far-daemon: the FAR collision-culling service. See README.md and docs/daemon.md.
#include <malloc.h>

#include <csignal>
#include <cstdio>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "daemon.h"
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "far/base/gpu_identity.h"
#include "far/gpu/gl_context.h"
#include "far/model/version.h"

namespace {

using far::server::DaemonConfig;

std::atomic<bool> g_stop{false};

void OnSignal(int) { g_stop = true; }  // async-signal-safe: a lock-free atomic store

// The command line: each setting flag reads into `flags` and, when given, overrides the config
// file's value (Apply).
struct CommandLine {
  CLI::App app{"far-daemon: GPU collision culling (FAR) for simulators over LCM + shared memory"};
  DaemonConfig flags;
  std::string config_path, gl_platform;
  bool list_gpus = false;
  std::vector<std::function<void(DaemonConfig&)>> overrides;

  // A flag for one field of DaemonConfig; its help shows the default when `show_default`.
  template <typename T>
  void Add(const std::string& name, T DaemonConfig::*field, const std::string& help,
           bool show_default = true) {
    CLI::Option* option = app.add_option(name, flags.*field, help);
    if (show_default) option->capture_default_str();
    if constexpr (std::is_same_v<T, std::vector<std::string>>) option->delimiter(',');
    overrides.push_back([this, option, field](DaemonConfig& config) {
      if (*option) config.*field = flags.*field;
    });
  }

  CommandLine() {
    app.set_version_flag("--version", std::string("far-daemon ") + far::kVersion);
    app.add_option("--config", config_path, "JSON config file (docs/daemon.md); flags override it");
    AddWhereFlags();
    AddLimitFlags();
    AddRunFlags();
  }

  // Where the daemon is: its name and socket, its GPU, its LCM URL.
  void AddWhereFlags() {
    Add("--name", &DaemonConfig::name,
        "this daemon's name: its socket <dir>/<name>.sock and LCM channel prefix; clients "
        "choose a daemon by name (far-client --daemon)");
    Add("--socket", &DaemonConfig::socket_path,
        "socket path (default: $FAR_SOCKET_DIR/<name>.sock when set, else /run/far/<name>.sock "
        "when /run/far exists, else $XDG_RUNTIME_DIR/far/<name>.sock, else "
        "/tmp/far-<uid>/<name>.sock, or $HOME/.far/run-<host>/<name>.sock when another user "
        "holds /tmp/far-<uid>)",
        false);
    Add("--gpu", &DaemonConfig::gpu,
        "EGL device index of the GPU to use, as --list-gpus numbers them (that device and no "
        "other; a second GPU gets a second daemon with its own --name)",
        false);
    Add("--gpu-id", &DaemonConfig::gpu_id,
        "the GPU by a name its scheduler gives it: a device minor number (the N of /dev/nvidiaN; "
        "Slurm's GPU index when gres.conf lists the devices in minor order), an NVIDIA UUID "
        "(GPU-...) or a PCI address; --list-gpus shows each device's names",
        false);
    Add("--serves-gpus", &DaemonConfig::serves_gpus,
        "comma-separated names this daemon also answers to when clients look for their job's "
        "GPU (far-client --daemon auto), beside those of its EGL device",
        false);
    app.add_flag("--list-gpus", list_gpus,
                 "list the EGL devices with their index and the names schedulers give them, and "
                 "exit");
    Add("--lcm-url", &DaemonConfig::lcm_url, "LCM URL");
    app.add_option("--gl-platform", gl_platform,
                   "auto (default: a GPU, else Mesa's software renderer), device (a GPU only: "
                   "fails without one) or surfaceless");
  }

  // What sessions and steps may ask for.
  void AddLimitFlags() {
    Add("--max-sessions", &DaemonConfig::max_sessions,
        "sessions of all users together, shared fairly by them");
    Add("--max-triangles", &DaemonConfig::max_triangles_per_session, "triangles per session");
    Add("--max-vertices", &DaemonConfig::max_vertices_per_session, "vertices per session");
    Add("--max-objects", &DaemonConfig::max_objects_per_session, "objects per session");
    Add("--max-resolution", &DaemonConfig::max_resolution,
        "largest viewport a request may ask for");
    Add("--ring-bytes", &DaemonConfig::ring_bytes, "update ring bytes per session (power of two)");
    Add("--max-rate", &DaemonConfig::max_requests_per_second,
        "step requests per second per session");
    Add("--max-sessions-per-user", &DaemonConfig::max_sessions_per_user,
        "sessions one user may hold (also the connections it may have waiting to say what they "
        "want)");
    Add("--max-opens-per-second", &DaemonConfig::max_opens_per_second_per_user,
        "sessions one user may open per second, sustained (bursts of as many)");
    Add("--max-triangles-total", &DaemonConfig::max_triangles_total,
        "triangles of all sessions together, shared fairly by their users (docs/daemon.md)");
    Add("--max-vertices-total", &DaemonConfig::max_vertices_total,
        "vertices of all sessions together, shared fairly by their users");
    Add("--max-segment-bytes-total", &DaemonConfig::max_segment_bytes_total,
        "shared-memory bytes of all sessions' segments together (0: max_sessions full ones)");
    Add("--session-idle-timeout", &DaemonConfig::session_idle_timeout_s,
        "seconds without a step after which a session is closed (0: never)");
    Add("--max-reply-pairs", &DaemonConfig::max_reply_pairs,
        "contact and distance pairs in one reply");
    Add("--step-deadline-ms", &DaemonConfig::step_deadline_ms,
        "the longest a step may wait and run");
    Add("--status-after-ms", &DaemonConfig::status_after_ms,
        "a step's statuses (queued, started, stage) are sent once it is this old; quicker steps "
        "get their reply alone (0: every status)");
  }

  // How it runs: threads, cores, the gpu method's batching and cost, logs and metrics.
  void AddRunFlags() {
    Add("--threads", &DaemonConfig::exact_threads, "CPU threads for exact tests (0: all)");
    Add("--gpu-batch", &DaemonConfig::gpu_batch,
        "the gpu method's steps of all sessions go to the GPU together, from one thread and "
        "context (true), or each session's on its own context in turns (false)");
    Add("--gpu-cost-cache", &DaemonConfig::gpu_cost_cache,
        "file that keeps auto's GPU cost between starts, so that a start on the same renderer, "
        "driver and CPUs skips the probe: a path, default ($XDG_CACHE_HOME/far/gpu-costs.json, "
        "else ~/.cache/far/gpu-costs.json) or off (measure at every start)",
        false);
    Add("--cpu-cores", &DaemonConfig::cpu_cores,
        "CPU cores the daemon may use in all (0: all): no session's threads exceed it (nor "
        "--threads), and a heavy session gets half of it");
    Add("--log-level", &DaemonConfig::log_level, "trace, debug, info, warn, error");
    Add("--metrics-file", &DaemonConfig::metrics_file,
        "write Prometheus metrics to this *.prom file for node_exporter's textfile collector "
        "(replaced atomically every --metrics-interval-s; its directory must exist)",
        false);
    Add("--metrics-port", &DaemonConfig::metrics_port,
        "serve Prometheus metrics at 127.0.0.1:PORT, path /metrics (loopback only; 0: no port)");
    Add("--metrics-interval-s", &DaemonConfig::metrics_interval_s,
        "seconds between rewrites of --metrics-file");
  }

  // The config file (when given), then every flag given on the command line on top of it.
  far::Result<DaemonConfig> Config() const {
    DaemonConfig config;
    if (!config_path.empty()) {
      auto loaded = far::server::LoadDaemonConfig(config_path);
      if (!loaded) return loaded.error();
      config = *loaded;
    }
    for (const auto& apply : overrides) apply(config);
    if (!gl_platform.empty()) {
      const std::optional<far::GlPlatform> platform = far::ParseGlPlatform(gl_platform);
      if (!platform) {
        return far::MakeError(
            far::ErrorCode::kInvalidArgument,
            "--gl-platform: unknown '" + gl_platform + "' (" + far::GlPlatformNames() + ")");
      }
      config.gl_platform = *platform;
    }
    if (auto ok = far::server::ValidateDaemonConfig(config); !ok) return ok.error();
    return config;
  }
};

}  // namespace

int main(int argc, char** argv) {
  CommandLine command_line;
  CLI11_PARSE(command_line.app, argc, argv);
  if (command_line.list_gpus) {
    const std::vector<far::GlContext::Device> devices = far::GlContext::ListDevices();
    if (devices.empty()) std::printf("no EGL devices (the EGL device platform is not offered)\n");
    for (const far::GlContext::Device& device : devices) {
      std::string names;
      for (const std::string& id : far::GpuIdentifiers(device.drm_device_file))
        names += (names.empty() ? "" : ", ") + id;
      std::printf("%s%s%s\n", device.description.c_str(),
                  names.empty() ? "" : " names: ", names.c_str());
    }
    return 0;
  }
  auto config = command_line.Config();
  if (!config) {
    std::fprintf(stderr, "far-daemon: %s\n", far::ToString(config.error()).c_str());
    return 2;
  }

  // Structured logs: one line per event, key=value.
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e level=%l %v");
  spdlog::set_level(spdlog::level::from_str(config->log_level));

  // Memory goes back to the system when sessions close (malloc_trim after each, see
  // SessionRegistry::ReapWorkers). Large buffers (meshes, ring records) stay on the heap up to
  // 32 MiB for reuse rather than costing a fresh zero-filled mmap each (bench/RESULTS.md, ring
  // ingest), and few arenas keep the many worker threads from scattering it.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_ARENA_MAX, 4);

  auto daemon = far::server::Daemon::Create(*config);
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
