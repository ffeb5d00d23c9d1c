#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

namespace far::server {

/// A token bucket: `rate` events per second sustained, bursts of up to `burst`. Used for a
/// session's step requests and a user's session opens. Not thread-safe (one owner thread).
class RateLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  RateLimiter(double rate, double burst) : rate_(rate), burst_(burst), tokens_(burst) {}

  /// Takes one token when there is one; false (and nothing taken) when over the rate.
  bool Allow(Clock::time_point now = Clock::now()) {
    if (last_ != Clock::time_point{}) {
      const double seconds = std::chrono::duration<double>(now - last_).count();
      tokens_ = std::min(burst_, tokens_ + seconds * rate_);
    }
    last_ = now;
    if (tokens_ < 1.0) return false;
    tokens_ -= 1.0;
    return true;
  }
  double rate() const { return rate_; }

 private:
  double rate_, burst_, tokens_;
  Clock::time_point last_{};
};

/// A rate as people write it: "20", "0.5", "2000" (std::to_string says "2000.000000").
inline std::string FormatRate(double per_second) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", per_second);
  return text;
}

}  // namespace far::server
