#pragma once

#include <sys/types.h>

#include <map>
#include <mutex>

#include "rate_limiter.h"

namespace far::server {

/// Per user, the CPU time of one-off work (StepControl's setup: hierarchy builds of new objects,
/// `auto`'s calibration steps) that does not count towards a step being heavy: a bucket of
/// `burst_ms`, refilled at a tenth of it per second. A session whose first step builds a large
/// scene's hierarchies is then judged on its steady steps, while a client that adds and removes
/// large objects at every step, or reopens sessions, gets at most a tenth of a core of
/// foreground setup over time, however many sessions it holds. Thread-safe.
class SetupAllowance {
 public:
  using Clock = RateLimiter::Clock;
  explicit SetupAllowance(double burst_ms) : burst_ms_(burst_ms) {}

  /// Takes up to `ms` from `uid`'s bucket; returns what it took.
  double TakeUpTo(uid_t uid, double ms, Clock::time_point now = Clock::now()) {
    std::lock_guard lock(mutex_);
    return BucketOf(uid).TakeUpTo(ms, now);
  }
  /// What `uid`'s bucket holds now.
  double Available(uid_t uid, Clock::time_point now = Clock::now()) {
    std::lock_guard lock(mutex_);
    return BucketOf(uid).Available(now);
  }

 private:
  RateLimiter& BucketOf(uid_t uid) {
    return buckets_.try_emplace(uid, burst_ms_ / 10, burst_ms_).first->second;
  }

  const double burst_ms_;
  std::mutex mutex_;
  std::map<uid_t, RateLimiter> buckets_;
};

}  // namespace far::server
