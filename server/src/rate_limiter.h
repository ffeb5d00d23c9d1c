#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

namespace far::server {

/// A token bucket: `rate` events per second sustained, bursts of up to `burst`. Used for a
/// session's step requests, a user's session opens and a user's setup allowance (tokens are
/// then milliseconds of CPU). Not thread-safe (one owner thread).
class RateLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  RateLimiter(double rate, double burst) : rate_(rate), burst_(burst), tokens_(burst) {}

  /// Takes one token when there is one; false (and nothing taken) when over the rate.
  bool Allow(Clock::time_point now = Clock::now()) {
    Refill(now);
    if (tokens_ < 1.0) return false;
    tokens_ -= 1.0;
    return true;
  }
  /// Takes up to `amount` (>= 0) of what the bucket holds; returns what it took.
  double TakeUpTo(double amount, Clock::time_point now = Clock::now()) {
    Refill(now);
    const double taken = std::clamp(amount, 0.0, tokens_);
    tokens_ -= taken;
    return taken;
  }
  /// What the bucket holds now.
  double Available(Clock::time_point now = Clock::now()) {
    Refill(now);
    return tokens_;
  }
  double rate() const { return rate_; }

 private:
  void Refill(Clock::time_point now) {
    if (last_ != Clock::time_point{} && now > last_) {
      const double seconds = std::chrono::duration<double>(now - last_).count();
      tokens_ = std::min(burst_, tokens_ + seconds * rate_);
    }
    if (now > last_) last_ = now;
  }

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
