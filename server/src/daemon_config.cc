#include "daemon_config.h"

#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "far/model/limits.h"

namespace far::server {
namespace {

Error Invalid(const std::string& key, const std::string& why) {
  return MakeError(ErrorCode::kInvalidArgument, "config '" + key + "': " + why);
}

// Reads one key (other than gl_platform) into `config`; false when the key is unknown.
bool ReadKey(const std::string& key, const nlohmann::json& value, DaemonConfig& config) {
  const auto set = [&](auto& field) {
    field = value.get<std::decay_t<decltype(field)>>();
    return true;
  };
  if (key == "name") return set(config.name);
  if (key == "socket_path") return set(config.socket_path);
  if (key == "lcm_url") return set(config.lcm_url);
  if (key == "gpu") return set(config.gpu);
  if (key == "max_sessions") return set(config.max_sessions);
  if (key == "max_sessions_per_user") return set(config.max_sessions_per_user);
  if (key == "max_opens_per_second_per_user") return set(config.max_opens_per_second_per_user);
  if (key == "max_objects_per_session") return set(config.max_objects_per_session);
  if (key == "max_triangles_per_session") return set(config.max_triangles_per_session);
  if (key == "max_vertices_per_session") return set(config.max_vertices_per_session);
  if (key == "max_triangles_total") return set(config.max_triangles_total);
  if (key == "max_vertices_total") return set(config.max_vertices_total);
  if (key == "ring_bytes") return set(config.ring_bytes);
  if (key == "reply_bytes") return set(config.reply_bytes);
  if (key == "max_resolution") return set(config.max_resolution);
  if (key == "max_requests_per_second") return set(config.max_requests_per_second);
  if (key == "max_queued_per_session") return set(config.max_queued_per_session);
  if (key == "max_reply_pairs") return set(config.max_reply_pairs);
  if (key == "step_deadline_ms") return set(config.step_deadline_ms);
  if (key == "heavy_step_ms") return set(config.heavy_step_ms);
  if (key == "exact_threads") return set(config.exact_threads);
  if (key == "log_level") return set(config.log_level);
  return false;
}

}  // namespace

Result<DaemonConfig> LoadDaemonConfig(const std::filesystem::path& path, DaemonConfig config) {
  std::ifstream file(path);
  if (!file) return MakeError(ErrorCode::kIoError, path.string() + ": cannot open");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(file);
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kParseError, path.string() + ": " + e.what());
  }
  if (!json.is_object())
    return MakeError(ErrorCode::kParseError, path.string() + ": not a JSON object");
  try {
    for (const auto& [key, value] : json.items()) {
      if (key == "gl_platform") {
        const auto name = value.get<std::string>();
        if (name == "auto")
          config.gl_platform = GlPlatform::kAuto;
        else if (name == "device")
          config.gl_platform = GlPlatform::kDevice;
        else if (name == "surfaceless")
          config.gl_platform = GlPlatform::kSurfaceless;
        else
          return Invalid(key, "unknown platform " + value.dump() + " (auto, device, surfaceless)");
      } else if (!ReadKey(key, value, config)) {
        return Invalid(key, "unknown key");
      }
    }
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kInvalidArgument, path.string() + ": wrong type: " + e.what());
  }
  if (auto ok = ValidateDaemonConfig(config); !ok.ok()) return ok.error();
  return config;
}

Result<void> ValidateDaemonConfig(const DaemonConfig& config) {
  if (!protocol::IsValidDaemonName(config.name))
    return Invalid("name",
                   "'" + config.name + "' is not 1..16 of [a-z0-9-] starting with a letter");
  if (config.lcm_url.empty()) return Invalid("lcm_url", "empty");
  if (config.gpu < -1) return Invalid("gpu", "must be -1 (any) or a device index >= 0");
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
  if (config.exact_threads < 0) return Invalid("exact_threads", "must be >= 0");
  static const std::set<std::string> kLevels = {"trace", "debug", "info", "warn", "error"};
  if (!kLevels.count(config.log_level))
    return Invalid("log_level",
                   "'" + config.log_level + "' is not one of trace, debug, info, warn, error");
  return {};
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

protocol::RingLimits RingLimitsOf(const DaemonConfig& config) {
  protocol::RingLimits limits;
  limits.max_vertices =
      static_cast<uint32_t>(std::min<int64_t>(config.max_vertices_per_session, 1 << 30));
  limits.max_triangles =
      static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session, 1 << 30));
  return limits;
}

}  // namespace far::server
