#pragma once

// far-daemon's GPU cost, kept between starts (docs/daemon.md, "The GPU cost at start-up").
// The probe that gives `auto` its GPU cost model (far::MeasureGpuCost) renders two scenes with
// two methods: seconds on a software rasterizer, and the same answer each time on the same
// renderer, driver, far and CPUs. So a daemon measures it once and keeps it in a small JSON
// file, which later starts read instead of measuring.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "far/base/result.h"
#include "far/pipeline/gpu_cost.h"

namespace far::server {

/// What a kept cost holds for: the renderer (GL_RENDERER), its driver (GL_VERSION), far's
/// version and this build of it (the binary's size and time), the probe's version and the CPUs
/// this process may run on (a software rasterizer's speed). A cost kept under another key is
/// never used.
std::string GpuCostKey(std::string_view renderer, std::string_view gl_version);

/// The default cache file: $XDG_CACHE_HOME/far/gpu-costs.json, else
/// $HOME/.cache/far/gpu-costs.json; "" when neither variable is set.
std::string DefaultGpuCostCachePath();

/// The file a gpu_cost_cache setting names: "" for "off", DefaultGpuCostCachePath() for "" and
/// "default".
std::string GpuCostCachePathOf(const std::string& setting);

/// A kept cost older than this is measured again (drivers and clocks change under a name).
inline constexpr int64_t kGpuCostMaxAgeSeconds = 30 * 24 * 3600;

/// The cost kept for `key` in the file at `path`, at time `now_unix_s`: nullopt when the file
/// does not exist or keeps nothing for the key, or kept it more than kGpuCostMaxAgeSeconds ago.
/// Errors: kIoError (the file exists but cannot be read, or is over 1 MiB), kParseError (not a
/// cache file, or the key's entry is not a valid cost: negative, not finite, over 10^6 ms).
Result<std::optional<GpuCost>> ReadCachedGpuCost(const std::string& path, const std::string& key,
                                                 int64_t now_unix_s);

/// Keeps `cost` for `key` in the file at `path` (made, with its directory, when missing),
/// beside what the file keeps for other keys (at most 31 of them, the newest; a file that is
/// not a cache file is replaced). The file is replaced atomically: a daemon starting beside
/// this one reads the old file or the new one; when two write at once, one's entry may be lost
/// and is measured again at its next start. Errors: kIoError.
Result<void> WriteCachedGpuCost(const std::string& path, const std::string& key,
                                const GpuCost& cost, int64_t now_unix_s);

/// The daemon's start-up, with its GL context current: auto's GPU cost read from the cache
/// file that `cache_setting` names (DaemonConfig::gpu_cost_cache), or measured and then kept
/// there. Returns "cached", "measured" or "unknown" (no context, or the probe failed); logs
/// event=gpu_cost and a warning when the file cannot be read or written (never an error: the
/// daemon then measures, as without a cache).
std::string PrepareGpuCost(const std::string& cache_setting, const std::string& renderer,
                           const std::string& gl_version);

}  // namespace far::server
