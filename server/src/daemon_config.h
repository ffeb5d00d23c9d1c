#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "far/gpu/gl_context.h"
#include "far/model/result.h"
#include "far/model/scene_model.h"
#include "far/protocol/channels.h"
#include "far/protocol/ring_records.h"

namespace far::server {

/// Everything far-daemon can be told, with defaults that work on the embedded llvmpipe.
/// Read from a JSON file (keys as below) and overridden by command-line flags.
struct DaemonConfig {
  std::string lcm_url = std::string(protocol::kDefaultLcmUrl);  ///< docs/protocol.md
  int max_resolution = 4096;  ///< larger requests are refused: one GL thread serves all
  GlPlatform gl_platform = GlPlatform::kAuto;
  int max_sessions = 64;
  int64_t max_triangles_per_session = 2'000'000;
  int64_t max_objects_per_session = 100'000;
  uint64_t ring_bytes = 64ull << 20;      ///< update ring per session (power of two): the most a
                                          ///< client may ask for
  uint64_t reply_bytes = 16ull << 20;     ///< reply ring per session (power of two): the same
  double max_requests_per_second = 2000;  ///< per session, sustained
  int max_queued_per_session = 4;
  int max_queued_total = 256;
  int heartbeat_timeout_ms = 5000;  ///< a session silent this long is closed
  int exact_threads = 0;            ///< CPU pool for exact tests (0: all cores)
  std::string log_level = "info";   ///< trace, debug, info, warn, error
};

/// Reads a JSON config file; unknown keys are errors (a typo must not be silently ignored).
/// Errors: kIoError, kParseError, kInvalidArgument naming the key and value.
Result<DaemonConfig> LoadDaemonConfig(const std::filesystem::path& path, DaemonConfig base = {});

/// Checks ranges. Errors: kInvalidArgument naming the field and value.
Result<void> ValidateDaemonConfig(const DaemonConfig& config);

/// A session's scene budgets (max_objects_per_session, max_triangles_per_session; vertices at
/// most three per triangle).
SceneLimits SceneLimitsOf(const DaemonConfig& config);

/// What one record of a session's update ring may carry (a record never exceeds the session's
/// budgets, nor 2^30 elements).
protocol::RingLimits RingLimitsOf(const DaemonConfig& config);

}  // namespace far::server
