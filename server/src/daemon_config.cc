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
      if (key == "lcm_url")
        config.lcm_url = value.get<std::string>();
      else if (key == "max_resolution")
        config.max_resolution = value.get<int>();
      else if (key == "gl_platform") {
        const auto name = value.get<std::string>();
        if (name == "auto")
          config.gl_platform = GlPlatform::kAuto;
        else if (name == "device")
          config.gl_platform = GlPlatform::kDevice;
        else if (name == "surfaceless")
          config.gl_platform = GlPlatform::kSurfaceless;
        else
          return Invalid(key, "unknown platform " + value.dump() + " (auto, device, surfaceless)");
      } else if (key == "max_sessions")
        config.max_sessions = value.get<int>();
      else if (key == "max_triangles_per_session")
        config.max_triangles_per_session = value.get<int64_t>();
      else if (key == "max_objects_per_session")
        config.max_objects_per_session = value.get<int64_t>();
      else if (key == "ring_bytes")
        config.ring_bytes = value.get<uint64_t>();
      else if (key == "reply_bytes")
        config.reply_bytes = value.get<uint64_t>();
      else if (key == "max_requests_per_second")
        config.max_requests_per_second = value.get<double>();
      else if (key == "max_queued_per_session")
        config.max_queued_per_session = value.get<int>();
      else if (key == "max_queued_total")
        config.max_queued_total = value.get<int>();
      else if (key == "heartbeat_timeout_ms")
        config.heartbeat_timeout_ms = value.get<int>();
      else if (key == "exact_threads")
        config.exact_threads = value.get<int>();
      else if (key == "log_level")
        config.log_level = value.get<std::string>();
      else
        return Invalid(key, "unknown key");
    }
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kInvalidArgument, path.string() + ": wrong type: " + e.what());
  }
  if (auto ok = ValidateDaemonConfig(config); !ok.ok()) return ok.error();
  return config;
}

Result<void> ValidateDaemonConfig(const DaemonConfig& config) {
  if (config.lcm_url.empty()) return Invalid("lcm_url", "empty");
  if (config.max_resolution < kMinResolution || config.max_resolution > kMaxResolution) {
    return Invalid("max_resolution", std::to_string(config.max_resolution) + " is outside [" +
                                         std::to_string(kMinResolution) + ", " +
                                         std::to_string(kMaxResolution) + "]");
  }
  if (config.max_sessions < 1) return Invalid("max_sessions", "must be >= 1");
  if (config.max_triangles_per_session < 1)
    return Invalid("max_triangles_per_session", "must be >= 1");
  if (config.max_objects_per_session < 1) return Invalid("max_objects_per_session", "must be >= 1");
  const auto power_of_two = [](uint64_t v) { return v != 0 && (v & (v - 1)) == 0; };
  if (!power_of_two(config.ring_bytes) || config.ring_bytes < (64u << 10) ||
      config.ring_bytes > (1ull << 30)) {
    return Invalid("ring_bytes",
                   std::to_string(config.ring_bytes) + " is not a power of two in [64 KiB, 1 GiB]");
  }
  if (config.reply_bytes < (64u << 10) || config.reply_bytes > (1ull << 30)) {
    return Invalid("reply_bytes",
                   std::to_string(config.reply_bytes) + " is outside [64 KiB, 1 GiB]");
  }
  if (!(config.max_requests_per_second > 0))
    return Invalid("max_requests_per_second", "must be > 0");
  if (config.max_queued_per_session < 1) return Invalid("max_queued_per_session", "must be >= 1");
  if (config.max_queued_total < config.max_queued_per_session) {
    return Invalid("max_queued_total", "must be >= max_queued_per_session");
  }
  if (config.heartbeat_timeout_ms < 100) return Invalid("heartbeat_timeout_ms", "must be >= 100");
  if (config.exact_threads < 0) return Invalid("exact_threads", "must be >= 0");
  static const std::set<std::string> kLevels = {"trace", "debug", "info", "warn", "error"};
  if (!kLevels.count(config.log_level))
    return Invalid("log_level",
                   "'" + config.log_level + "' is not one of trace, debug, info, warn, error");
  return {};
}

SceneLimits SceneLimitsOf(const DaemonConfig& config) {
  SceneLimits limits;
  limits.max_objects = config.max_objects_per_session;
  limits.max_triangles = config.max_triangles_per_session;
  limits.max_vertices = 3 * config.max_triangles_per_session;
  return limits;
}

protocol::RingLimits RingLimitsOf(const DaemonConfig& config) {
  protocol::RingLimits limits;
  limits.max_vertices =
      static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session * 3, 1 << 30));
  limits.max_triangles =
      static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session, 1 << 30));
  return limits;
}

}  // namespace far::server
