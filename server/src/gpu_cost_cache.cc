#include "gpu_cost_cache.h"

#include <sched.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "atomic_file.h"
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "far/model/version.h"
#include "far/pipeline/pipeline.h"

namespace far::server {
namespace {

constexpr std::string_view kFormat = "far-gpu-costs/1";
// Bumped whenever the probe's scenes or methods change (far/pipeline/src/gpu_probe.cc).
constexpr int kProbeVersion = 1;
constexpr uintmax_t kMaxFileBytes = 1 << 20;
constexpr size_t kMaxEntries = 32;
constexpr double kMaxMs = 1e6;

// This build of the daemon: its binary's size and modification time, so that a rebuild (a
// developer's, or a package upgrade within one version) measures again.
std::string ThisBuild() {
  struct stat binary {};
  if (stat("/proc/self/exe", &binary) != 0) return "unknown";
  return std::to_string(binary.st_size) + "-" + std::to_string(binary.st_mtime);
}

int UsableCpus() {
  cpu_set_t cpus;
  if (sched_getaffinity(0, sizeof cpus, &cpus) != 0) return 0;
  return CPU_COUNT(&cpus);
}

Error FileError(ErrorCode code, const std::string& path, const std::string& what) {
  return MakeError(code, "gpu_cost_cache '" + path + "': " + what);
}

// A cost in milliseconds as the cache keeps it: a finite number in [0, 10^6].
std::optional<double> Milliseconds(const nlohmann::json& entry, const char* name) {
  const auto it = entry.find(name);
  if (it == entry.end() || !it->is_number()) return std::nullopt;
  const double ms = it->get<double>();
  if (!std::isfinite(ms) || ms < 0 || ms > kMaxMs) return std::nullopt;
  return ms;
}

// The cost an entry keeps; nullopt when any field is missing or out of range.
std::optional<GpuCost> CostOf(const nlohmann::json& entry) {
  if (!entry.is_object()) return std::nullopt;
  const auto fixed = Milliseconds(entry, "fixed_ms");
  const auto per_triangle = Milliseconds(entry, "ms_per_triangle");
  if (!fixed || !per_triangle) return std::nullopt;
  GpuCost cost{*fixed, *per_triangle};
  const bool has_compute = entry.contains("compute_fixed_ms");
  if (has_compute != entry.contains("compute_ms_per_triangle")) return std::nullopt;
  if (has_compute) {
    cost.compute_fixed_ms = Milliseconds(entry, "compute_fixed_ms");
    cost.compute_ms_per_triangle = Milliseconds(entry, "compute_ms_per_triangle");
    if (!cost.compute_fixed_ms || !cost.compute_ms_per_triangle) return std::nullopt;
  }
  return cost;
}

int64_t MeasuredAt(const nlohmann::json& entry) {
  const auto it = entry.find("measured_unix_s");
  return it != entry.end() && it->is_number_integer() ? it->get<int64_t>() : 0;
}

// The file's entries (its "costs" object). nullopt: the file does not exist.
Result<std::optional<nlohmann::json>> ReadEntries(const std::string& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (status.type() == std::filesystem::file_type::not_found)
    return std::optional<nlohmann::json>();
  if (error) return FileError(ErrorCode::kIoError, path, error.message());
  if (!std::filesystem::is_regular_file(status))
    return FileError(ErrorCode::kIoError, path, "not a regular file");
  const uintmax_t size = std::filesystem::file_size(path, error);
  if (error) return FileError(ErrorCode::kIoError, path, error.message());
  if (size > kMaxFileBytes)
    return FileError(ErrorCode::kIoError, path,
                     std::to_string(size) + " bytes, over the " + std::to_string(kMaxFileBytes) +
                         " a cache file may have");
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  if (!file) return FileError(ErrorCode::kIoError, path, "cannot be read");
  const nlohmann::json json =
      nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  // (nlohmann's value() would throw on a "format" that is not a string: checked by hand.)
  const auto format = json.is_object() ? json.find("format") : json.end();
  if (format == json.end() || !format->is_string() || format->get<std::string>() != kFormat ||
      !json.contains("costs") || !json["costs"].is_object())
    return FileError(ErrorCode::kParseError, path,
                     "not a far GPU cost cache (format \"" + std::string(kFormat) + "\")");
  return std::optional<nlohmann::json>(json["costs"]);
}

int64_t NowUnixSeconds() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string Describe(const GpuCost& cost) {
  std::ostringstream text;
  text << "fixed_ms=" << cost.fixed_ms << " ms_per_triangle=" << cost.ms_per_triangle;
  if (cost.compute_fixed_ms && cost.compute_ms_per_triangle) {
    text << " compute_fixed_ms=" << *cost.compute_fixed_ms
         << " compute_ms_per_triangle=" << *cost.compute_ms_per_triangle;
  }
  return text.str();
}

}  // namespace

std::string GpuCostKey(std::string_view renderer, std::string_view gl_version) {
  std::ostringstream key;
  key << renderer << " | " << gl_version << " | far " << kVersion << " build " << ThisBuild()
      << " | probe " << kProbeVersion << " | cpus " << UsableCpus();
  return key.str();
}

std::string DefaultGpuCostCachePath() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && xdg[0] == '/') return std::string(xdg) + "/far/gpu-costs.json";
  const char* home = std::getenv("HOME");
  if (home != nullptr && home[0] == '/') return std::string(home) + "/.cache/far/gpu-costs.json";
  return "";
}

std::string GpuCostCachePathOf(const std::string& setting) {
  if (setting == "off") return "";
  return setting.empty() || setting == "default" ? DefaultGpuCostCachePath() : setting;
}

Result<std::optional<GpuCost>> ReadCachedGpuCost(const std::string& path, const std::string& key,
                                                 int64_t now_unix_s) {
  auto entries = ReadEntries(path);
  if (!entries) return entries.error();
  if (!*entries || !(*entries)->contains(key)) return std::optional<GpuCost>();
  const nlohmann::json& entry = (**entries)[key];
  const std::optional<GpuCost> cost = CostOf(entry);
  if (!cost) return FileError(ErrorCode::kParseError, path, "the entry for this GPU is invalid");
  const int64_t age = now_unix_s - MeasuredAt(entry);
  if (age < 0 || age > kGpuCostMaxAgeSeconds) return std::optional<GpuCost>();
  return cost;
}

Result<void> WriteCachedGpuCost(const std::string& path, const std::string& key,
                                const GpuCost& cost, int64_t now_unix_s) {
  // The other keys' entries, newest first, so that the oldest go when there are too many.
  std::vector<std::pair<std::string, nlohmann::json>> others;
  if (auto entries = ReadEntries(path); entries && *entries) {
    for (const auto& [other, entry] : (*entries)->items()) {
      if (other != key && CostOf(entry)) others.emplace_back(other, entry);
    }
  }
  std::sort(others.begin(), others.end(), [](const auto& a, const auto& b) {
    return MeasuredAt(a.second) > MeasuredAt(b.second);
  });
  if (others.size() > kMaxEntries - 1) others.resize(kMaxEntries - 1);
  nlohmann::json costs = nlohmann::json::object();
  for (auto& [other, entry] : others) costs[other] = std::move(entry);
  nlohmann::json& entry = costs[key];
  entry["measured_unix_s"] = now_unix_s;
  entry["fixed_ms"] = cost.fixed_ms;
  entry["ms_per_triangle"] = cost.ms_per_triangle;
  if (cost.compute_fixed_ms && cost.compute_ms_per_triangle) {
    entry["compute_fixed_ms"] = *cost.compute_fixed_ms;
    entry["compute_ms_per_triangle"] = *cost.compute_ms_per_triangle;
  }
  const nlohmann::json file = {{"format", kFormat}, {"costs", std::move(costs)}};
  std::error_code error;
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  if (!directory.empty()) std::filesystem::create_directories(directory, error);
  if (error)
    return FileError(ErrorCode::kIoError, path, "cannot make its directory: " + error.message());
  if (auto written = WriteFileAtomically(path, file.dump(2) + "\n"); !written)
    return MakeError(ErrorCode::kIoError, "gpu_cost_cache " + written.error().message);
  return {};
}

std::string PrepareGpuCost(const std::string& cache_setting, const std::string& renderer,
                           const std::string& gl_version) {
  const std::string path = GpuCostCachePathOf(cache_setting);
  const std::string key = GpuCostKey(renderer, gl_version);
  const int64_t now = NowUnixSeconds();
  if (!path.empty()) {
    auto cached = ReadCachedGpuCost(path, key, now);
    if (!cached) {
      spdlog::warn("event=gpu_cost_cache_unreadable message=\"{}\" action=measure",
                   cached.error().message);
    } else if (*cached && UseGpuCost(**cached)) {
      spdlog::info("event=gpu_cost source=cached file=\"{}\" {}", path, Describe(**cached));
      return "cached";
    }
  }
  const std::optional<GpuCost> measured = MeasureGpuCost();
  if (!measured) {
    spdlog::warn("event=gpu_cost_unknown renderer=\"{}\"", renderer);
    return "unknown";
  }
  spdlog::info("event=gpu_cost source=measured file=\"{}\" {}", path, Describe(*measured));
  if (!path.empty()) {
    if (auto kept = WriteCachedGpuCost(path, key, *measured, now); !kept) {
      spdlog::warn("event=gpu_cost_cache_unwritable message=\"{}\"", kept.error().message);
    }
  }
  return "measured";
}

}  // namespace far::server
