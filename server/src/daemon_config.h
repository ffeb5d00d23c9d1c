#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "far/base/result.h"
#include "far/gpu/gl_platform.h"
#include "far/model/scene_budget.h"
#include "far/model/scene_model.h"
#include "far/protocol/channels.h"
#include "far/protocol/ring_records.h"

namespace far::server {

/// Everything far-daemon can be told, with defaults that work on the embedded llvmpipe.
/// Read from a JSON file (keys as below) and overridden by command-line flags. docs/daemon.md
/// explains each.
struct DaemonConfig {
  // Where the daemon is.
  std::string name = std::string(protocol::kDefaultDaemonName);  ///< socket and channel prefix
  std::string socket_path;  ///< "" = protocol::DefaultSocketPath(name)
  std::string lcm_url = std::string(protocol::kDefaultLcmUrl);  ///< docs/protocol.md
  GlPlatform gl_platform = GlPlatform::kAuto;
  int gpu = -1;  ///< EGL device index (far-daemon --gpu N); -1: the first that works
  /// The GPU by a name its scheduler gives it (far-daemon --gpu-id): a device minor number
  /// ("2", Slurm's index when gres.conf lists the devices in minor order), an NVIDIA UUID or a
  /// PCI address; "" = by `gpu`. The EGL
  /// device whose far::GpuIdentifiers include it is used (docs/cluster.md).
  std::string gpu_id;
  /// More names the daemon answers to when clients look for their job's GPU (far-client
  /// --daemon auto), beside those detected from its EGL device: for schedulers that number
  /// GPUs their own way, and for daemons on a software renderer standing in for a GPU.
  std::vector<std::string> serves_gpus;
  /// The gpu method's GPU work of every session goes to one thread and context that issues the
  /// steps waiting at the time together (far::ComputeBatcher); false: each session issues its
  /// own on its own context, in turns under the GL lock.
  bool gpu_batch = true;
  /// The file auto's GPU cost is kept in between starts (gpu_cost_cache.h): "" or "default" =
  /// $XDG_CACHE_HOME/far/gpu-costs.json (else ~/.cache/far/gpu-costs.json); "off" = measure
  /// at every start.
  std::string gpu_cost_cache;
  // Sessions.
  int max_sessions = 64;
  int max_sessions_per_user = 16;
  double max_opens_per_second_per_user = 20;  ///< sustained; bursts of as many
  int64_t max_objects_per_session = 100'000;
  int64_t max_triangles_per_session = 2'000'000;
  int64_t max_vertices_per_session = 6'000'000;
  int64_t max_triangles_total = 8'000'000;  ///< all sessions together
  int64_t max_vertices_total = 16'000'000;  ///< all sessions together
  /// Shared-memory bytes of all sessions' segments together; 0: as much as max_sessions
  /// sessions with the largest rings take (BudgetTotalsOf).
  int64_t max_segment_bytes_total = 0;
  /// A session that has not stepped for this long (no step queued, running or ended) is
  /// closed and its client told why; 0: never.
  double session_idle_timeout_s = 600;
  uint64_t ring_bytes = 64ull << 20;   ///< update ring per session (power of two): the most a
                                       ///< client may ask for
  uint64_t reply_bytes = 16ull << 20;  ///< reply ring per session (power of two): the same
  // Steps.
  int max_resolution = 4096;              ///< larger requests are refused
  double max_requests_per_second = 2000;  ///< per session, sent while one waits; sustained
  int max_queued_per_session = 4;
  int64_t max_reply_pairs = 2'000'000;  ///< contacts + distance pairs in one reply
  int step_deadline_ms = 60'000;        ///< the longest a step may wait and run
  int heavy_step_ms = 50;  ///< a session whose step takes longer runs at a lower CPU priority
  /// A step's statuses (queued, started, stage) are sent once it is this old (ms since its
  /// request came); a step answered sooner gets its reply alone. "queued" is sent at once when
  /// the step waits behind another. 0: every status, as soon as it happens.
  int status_after_ms = 5;
  /// Per user, ms of one-off work (hierarchy builds, auto's calibration) that does not make a
  /// step heavy; refilled at a tenth of it per second (setup_allowance.h). 0: every step's
  /// whole CPU time counts.
  double setup_allowance_ms = 1000;
  int exact_threads = 0;  ///< CPU threads per session for the exact tests (0: all cores)
  /// CPU cores the daemon may use in all (0: all, std::thread::hardware_concurrency()): no
  /// session's pool has more threads, and a heavy session's loops get half of them.
  int cpu_cores = 0;
  std::string log_level = "info";  ///< trace, debug, info, warn, error
  // Metrics (Prometheus' text format; metrics_export.h).
  /// node_exporter's textfile collector reads this file (a *.prom in an existing directory),
  /// rewritten atomically every metrics_interval_s; "": none.
  std::string metrics_file;
  int metrics_port = 0;           ///< serves /metrics on 127.0.0.1 only; 0: none
  double metrics_interval_s = 5;  ///< how often metrics_file is rewritten, seconds
};

/// Reads a JSON config file; unknown keys are errors (a typo must not be silently ignored).
/// Errors: kIoError, kParseError, kInvalidArgument naming the key and value.
Result<DaemonConfig> LoadDaemonConfig(const std::filesystem::path& path, DaemonConfig base = {});

/// As LoadDaemonConfig, for the file's text held in memory; `name_for_errors` starts every
/// error message (LoadDaemonConfig passes the path). Errors: kParseError, kInvalidArgument.
Result<DaemonConfig> ParseDaemonConfig(std::string_view text, std::string_view name_for_errors,
                                       DaemonConfig base = {});

/// Checks ranges. Errors: kInvalidArgument naming the field and value.
Result<void> ValidateDaemonConfig(const DaemonConfig& config);

/// The most cpu_cores may say.
inline constexpr int kMaxCpuCores = 4096;

/// The cores the daemon uses: cpu_cores, or the machine's (at least 1) when it is 0.
int CpuCoresOf(const DaemonConfig& config);

/// The socket path: socket_path, or the default for the name.
std::string SocketPathOf(const DaemonConfig& config);

/// A session's scene budgets (max_objects_per_session, max_triangles_per_session,
/// max_vertices_per_session).
SceneLimits SceneLimitsOf(const DaemonConfig& config);

/// The daemon-wide budgets its users share (far/model/scene_budget.h): max_sessions,
/// max_segment_bytes_total (or its default), max_vertices_total, max_triangles_total.
BudgetAmounts BudgetTotalsOf(const DaemonConfig& config);

/// What one record of a session's update ring may carry (a record never exceeds the session's
/// budgets, nor 2^30 elements).
protocol::RingLimits RingLimitsOf(const DaemonConfig& config);

}  // namespace far::server
