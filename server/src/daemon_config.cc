#include "daemon_config.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <thread>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

#include "far/base/limits.h"
#include "far/protocol/ring_layout.h"

namespace far::server {
namespace {

Error Invalid(const std::string& key, const std::string& why) {
  return MakeError(ErrorCode::kInvalidArgument, "config '" + key + "': " + why);
}

// Reads a JSON number into `out`. nlohmann's get<T> converts any number (and booleans) with a
// plain cast: 1e10 into an int or 1e29 into a uint64_t is undefined behaviour, 4294967297 into
// an int silently becomes 1. So integers must be JSON integers within T's range.
template <typename T>
Result<void> ReadNumber(const std::string& key, const nlohmann::json& value, T* out) {
  if constexpr (std::is_floating_point_v<T>) {
    if (value.is_number()) {
      *out = value.get<T>();
      return {};
    }
    return Invalid(key, value.dump() + " is not a number");
  } else {
    if (value.is_number_unsigned() && std::in_range<T>(value.get<uint64_t>())) {
      *out = static_cast<T>(value.get<uint64_t>());
      return {};
    }
    if (value.is_number_integer() && !value.is_number_unsigned() &&
        std::in_range<T>(value.get<int64_t>())) {
      *out = static_cast<T>(value.get<int64_t>());
      return {};
    }
    return Invalid(key, value.dump() + " is not an integer in [" +
                            std::to_string(std::numeric_limits<T>::min()) + ", " +
                            std::to_string(std::numeric_limits<T>::max()) + "]");
  }
}

// A name a scheduler gives a GPU: "2", "GPU-6f0e...", "0000:3b:00.0".
bool IsGpuName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == ':' || c == '.' || c == '_' || c == '-';
  });
}
constexpr size_t kMaxServedGpuNames = 16;

Result<void> ReadPlatform(const std::string& key, const nlohmann::json& value, GlPlatform* out) {
  const std::optional<GlPlatform> platform = ParseGlPlatform(value.get<std::string>());
  if (!platform) {
    return Invalid(key, "unknown platform " + value.dump() + " (" + GlPlatformNames() + ")");
  }
  *out = *platform;
  return {};
}

// Sets the field `key` names. Throws nlohmann's type_error for a string field of another type.
Result<void> ReadKey(const std::string& key, const nlohmann::json& value, DaemonConfig& config) {
  const auto set = [&](auto& field) -> Result<void> {
    if constexpr (std::is_same_v<std::decay_t<decltype(field)>, std::string>) {
      field = value.get<std::string>();
      return {};
    } else if constexpr (std::is_same_v<std::decay_t<decltype(field)>, bool>) {
      if (!value.is_boolean()) return Invalid(key, value.dump() + " is not true or false");
      field = value.get<bool>();
      return {};
    } else {
      return ReadNumber(key, value, &field);
    }
  };
  if (key == "gl_platform") return ReadPlatform(key, value, &config.gl_platform);
  if (key == "name") return set(config.name);
  if (key == "socket_path") return set(config.socket_path);
  if (key == "lcm_url") return set(config.lcm_url);
  if (key == "gpu") return set(config.gpu);
  if (key == "gpu_id") return set(config.gpu_id);
  if (key == "gpu_batch") return set(config.gpu_batch);
  if (key == "gpu_cost_cache") return set(config.gpu_cost_cache);
  if (key == "serves_gpus") {
    config.serves_gpus = value.get<std::vector<std::string>>();
    return {};
  }
  if (key == "max_sessions") return set(config.max_sessions);
  if (key == "max_sessions_per_user") return set(config.max_sessions_per_user);
  if (key == "max_opens_per_second_per_user") return set(config.max_opens_per_second_per_user);
  if (key == "max_objects_per_session") return set(config.max_objects_per_session);
  if (key == "max_triangles_per_session") return set(config.max_triangles_per_session);
  if (key == "max_vertices_per_session") return set(config.max_vertices_per_session);
  if (key == "max_triangles_total") return set(config.max_triangles_total);
  if (key == "max_vertices_total") return set(config.max_vertices_total);
  if (key == "max_segment_bytes_total") return set(config.max_segment_bytes_total);
  if (key == "session_idle_timeout_s") return set(config.session_idle_timeout_s);
  if (key == "ring_bytes") return set(config.ring_bytes);
  if (key == "reply_bytes") return set(config.reply_bytes);
  if (key == "max_resolution") return set(config.max_resolution);
  if (key == "max_requests_per_second") return set(config.max_requests_per_second);
  if (key == "max_queued_per_session") return set(config.max_queued_per_session);
  if (key == "max_reply_pairs") return set(config.max_reply_pairs);
  if (key == "step_deadline_ms") return set(config.step_deadline_ms);
  if (key == "heavy_step_ms") return set(config.heavy_step_ms);
  if (key == "status_after_ms") return set(config.status_after_ms);
  if (key == "setup_allowance_ms") return set(config.setup_allowance_ms);
  if (key == "exact_threads") return set(config.exact_threads);
  if (key == "cpu_cores") return set(config.cpu_cores);
  if (key == "log_level") return set(config.log_level);
  if (key == "metrics_file") return set(config.metrics_file);
  if (key == "metrics_port") return set(config.metrics_port);
  if (key == "metrics_interval_s") return set(config.metrics_interval_s);
  return Invalid(key, "unknown key");
}

// The metrics file must be one node_exporter's textfile collector reads (it reads *.prom only)
// in a directory that exists: the daemon writes a temporary file beside it and renames it over
// the file, and a directory missing at start would only show as a warning at each write.
Result<void> ValidateMetrics(const DaemonConfig& config) {
  if (config.metrics_port < 0 || config.metrics_port > 65535)
    return Invalid("metrics_port",
                   std::to_string(config.metrics_port) + " is outside [0, 65535] (0: no port)");
  if (!(config.metrics_interval_s >= 0.1 && config.metrics_interval_s <= 3600))
    return Invalid("metrics_interval_s", "must be in [0.1, 3600] seconds");
  if (config.metrics_file.empty()) return {};
  const std::filesystem::path file(config.metrics_file);
  if (file.extension() != ".prom")
    return Invalid("metrics_file", "'" + config.metrics_file +
                                       "' does not end in .prom, the files node_exporter's "
                                       "textfile collector reads");
  const std::filesystem::path directory =
      file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error))
    return Invalid("metrics_file", "'" + config.metrics_file + "': its directory '" +
                                       directory.string() + "' does not exist");
  return {};
}

}  // namespace

Result<DaemonConfig> LoadDaemonConfig(const std::filesystem::path& path, DaemonConfig base) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return MakeError(ErrorCode::kIoError, path.string() + ": cannot open");
  std::ostringstream text;
  text << file.rdbuf();
  return ParseDaemonConfig(text.str(), path.string(), std::move(base));
}

Result<DaemonConfig> ParseDaemonConfig(std::string_view text, std::string_view name_for_errors,
                                       DaemonConfig config) {
  const std::string name(name_for_errors);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kParseError, name + ": " + e.what());
  }
  if (!json.is_object()) return MakeError(ErrorCode::kParseError, name + ": not a JSON object");
  try {
    for (const auto& [key, value] : json.items()) {
      if (auto read = ReadKey(key, value, config); !read) return read.error();
    }
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kInvalidArgument, name + ": wrong type: " + e.what());
  }
  if (auto ok = ValidateDaemonConfig(config); !ok.ok()) return ok.error();
  return config;
}

Result<void> ValidateDaemonConfig(const DaemonConfig& config) {
  if (!protocol::IsValidDaemonName(config.name))
    return Invalid("name",
                   "'" + config.name + "' is not 1..16 of [a-z0-9-] starting with a letter");
  if (config.name == "auto")
    return Invalid("name", "'auto' is reserved: clients' --daemon auto chooses a daemon");
  if (config.lcm_url.empty()) return Invalid("lcm_url", "empty");
  if (config.gpu < -1) return Invalid("gpu", "must be -1 (any) or a device index >= 0");
  if (!config.gpu_id.empty() && config.gpu >= 0)
    return Invalid("gpu_id", "give the GPU by index (gpu) or by name (gpu_id), not both");
  if (!config.gpu_id.empty() && !IsGpuName(config.gpu_id))
    return Invalid("gpu_id", "'" + config.gpu_id + "' is not 1..64 of [A-Za-z0-9:._-]");
  if (config.serves_gpus.size() > kMaxServedGpuNames)
    return Invalid("serves_gpus", "more than " + std::to_string(kMaxServedGpuNames) + " names");
  for (const std::string& gpu_name : config.serves_gpus) {
    if (!IsGpuName(gpu_name))
      return Invalid("serves_gpus", "'" + gpu_name + "' is not 1..64 of [A-Za-z0-9:._-]");
  }
  if (config.max_resolution < kMinResolution || config.max_resolution > kMaxResolution) {
    return Invalid("max_resolution", std::to_string(config.max_resolution) + " is outside [" +
                                         std::to_string(kMinResolution) + ", " +
                                         std::to_string(kMaxResolution) + "]");
  }
  if (config.max_sessions < 1) return Invalid("max_sessions", "must be >= 1");
  if (config.max_sessions_per_user < 1) return Invalid("max_sessions_per_user", "must be >= 1");
  if (!(config.max_opens_per_second_per_user > 0))
    return Invalid("max_opens_per_second_per_user", "must be > 0");
  for (const auto& [key, value] :
       {std::pair{"max_objects_per_session", config.max_objects_per_session},
        {"max_triangles_per_session", config.max_triangles_per_session},
        {"max_vertices_per_session", config.max_vertices_per_session},
        {"max_triangles_total", config.max_triangles_total},
        {"max_vertices_total", config.max_vertices_total},
        {"max_reply_pairs", config.max_reply_pairs}}) {
    if (value < 1) return Invalid(key, "must be >= 1");
  }
  if (config.max_segment_bytes_total < 0)
    return Invalid("max_segment_bytes_total", "must be >= 0 (0: by max_sessions)");
  if (!(config.session_idle_timeout_s == 0 ||
        (config.session_idle_timeout_s >= 1 && config.session_idle_timeout_s <= 604'800)))
    return Invalid("session_idle_timeout_s", "must be 0 (never) or in [1, 604800]");
  const auto power_of_two = [](uint64_t v) { return v != 0 && (v & (v - 1)) == 0; };
  for (const auto& [key, value] :
       {std::pair{"ring_bytes", config.ring_bytes}, {"reply_bytes", config.reply_bytes}}) {
    if (!power_of_two(value) || value < (64u << 10) || value > (1ull << 30))
      return Invalid(key, std::to_string(value) + " is not a power of two in [64 KiB, 1 GiB]");
  }
  if (!(config.max_requests_per_second > 0))
    return Invalid("max_requests_per_second", "must be > 0");
  if (config.max_queued_per_session < 1) return Invalid("max_queued_per_session", "must be >= 1");
  if (config.step_deadline_ms < 100) return Invalid("step_deadline_ms", "must be >= 100");
  if (config.heavy_step_ms < 1) return Invalid("heavy_step_ms", "must be >= 1");
  if (config.status_after_ms < 0 || config.status_after_ms > 60'000)
    return Invalid("status_after_ms", "must be in [0, 60000]");
  if (!(config.setup_allowance_ms >= 0 && config.setup_allowance_ms <= 3.6e6))
    return Invalid("setup_allowance_ms", "must be in [0, 3600000]");
  if (config.exact_threads < 0) return Invalid("exact_threads", "must be >= 0");
  if (config.cpu_cores < 0 || config.cpu_cores > kMaxCpuCores)
    return Invalid("cpu_cores", std::to_string(config.cpu_cores) + " is outside [0, " +
                                    std::to_string(kMaxCpuCores) + "] (0: all cores)");
  if (auto ok = ValidateMetrics(config); !ok) return ok;
  static const std::set<std::string> kLevels = {"trace", "debug", "info", "warn", "error"};
  if (!kLevels.count(config.log_level))
    return Invalid("log_level",
                   "'" + config.log_level + "' is not one of trace, debug, info, warn, error");
  return {};
}

int CpuCoresOf(const DaemonConfig& config) {
  if (config.cpu_cores > 0) return config.cpu_cores;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

std::string SocketPathOf(const DaemonConfig& config) {
  return config.socket_path.empty() ? protocol::DefaultSocketPath(config.name) : config.socket_path;
}

SceneLimits SceneLimitsOf(const DaemonConfig& config) {
  SceneLimits limits;
  limits.max_objects = config.max_objects_per_session;
  limits.max_triangles = config.max_triangles_per_session;
  limits.max_vertices = config.max_vertices_per_session;
  return limits;
}

BudgetAmounts BudgetTotalsOf(const DaemonConfig& config) {
  BudgetAmounts totals;
  totals[BudgetKind::kSessions] = config.max_sessions;
  const uint64_t segment =
      protocol::MakeSegmentLayout(config.ring_bytes, config.reply_bytes).segment_size;
  totals[BudgetKind::kSegmentBytes] =
      config.max_segment_bytes_total > 0
          ? config.max_segment_bytes_total
          : static_cast<int64_t>(segment) * std::max(1, config.max_sessions);
  totals[BudgetKind::kVertices] = config.max_vertices_total;
  totals[BudgetKind::kTriangles] = config.max_triangles_total;
  return totals;
}

protocol::RingLimits RingLimitsOf(const DaemonConfig& config) {
  protocol::RingLimits limits;
  limits.max_vertices =
      static_cast<uint32_t>(std::min<int64_t>(config.max_vertices_per_session, 1 << 30));
  limits.max_triangles =
      static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session, 1 << 30));
  return limits;
}

}  // namespace far::server
