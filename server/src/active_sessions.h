#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <unordered_map>

namespace far::server {

/// The sessions that stepped within the last second: how many simulators share the daemon's
/// cores now. A session's pipeline counts on cpu_cores over that many (Pipeline::SetCpuShare),
/// so that auto weighs a configuration's CPU time as the other sessions feel it.
/// Thread-safe.
class ActiveSessions {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::seconds kWindow{1};

  /// Notes that `session` steps now; returns the sessions that stepped within kWindow, this one
  /// included.
  int Stepping(int64_t session, Clock::time_point now = Clock::now()) {
    std::lock_guard lock(mutex_);
    last_step_[session] = now;
    int active = 0;
    for (auto it = last_step_.begin(); it != last_step_.end();) {
      if (now - it->second > kWindow) {
        it = last_step_.erase(it);
      } else {
        ++active;
        ++it;
      }
    }
    return active;
  }

 private:
  std::mutex mutex_;
  std::unordered_map<int64_t, Clock::time_point> last_step_;
};

}  // namespace far::server
