#include "cli_common.h"

#include <cmath>

namespace far::cli {

Result<std::chrono::milliseconds> ParseDuration(const std::string& flag, const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = text.substr(used);
  double ms_per_unit = 0;
  if (unit.empty() || unit == "s") {
    ms_per_unit = 1000;
  } else if (unit == "ms") {
    ms_per_unit = 1;
  } else if (unit == "m" || unit == "min") {
    ms_per_unit = 60'000;
  }
  const double ms = value * ms_per_unit;
  if (used == 0 || ms_per_unit == 0 || !std::isfinite(ms) || ms <= 0 || ms > 86'400'000) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        flag + ": '" + text + "' is not a duration between 1 ms and 24 h, like 500ms, 60s or 2m");
  }
  return std::chrono::milliseconds(static_cast<int64_t>(std::ceil(ms)));
}

Result<client::ClientOptions> GlobalFlags::Options() const {
  client::ClientOptions o = options;
  auto connect = ParseDuration("--connect-timeout", connect_timeout);
  if (!connect) return connect.error();
  o.connect_timeout = *connect;
  return o;
}

}  // namespace far::cli
