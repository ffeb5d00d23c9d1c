#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <utility>

#include "far/model/result.h"

namespace far::server {

/// Limits that keep one client from starving the others or growing memory without bound.
struct SchedulerLimits {
  size_t max_queued_per_session = 4;   ///< more pending requests of one session: busy
  size_t max_queued_total = 256;       ///< more pending requests overall: busy
  double max_rate_per_session = 1000;  ///< requests per second a session may submit (sustained)
  double burst_per_session = 50;       ///< requests a session may submit at once
};

/// Round-robin scheduling of jobs across sessions, with bounded queues and a per-session token
/// bucket. A session that floods gets "busy" instead of being served ahead of the others.
/// Not thread-safe: the daemon guards it with its own mutex.
template <typename Job>
class FairScheduler {
 public:
  using Clock = std::chrono::steady_clock;
  explicit FairScheduler(const SchedulerLimits& limits) : limits_(limits) {}

  /// Queues `job` for `session`. Errors: kBusy (queue full, or over the request rate).
  Result<void> Push(int64_t session, Job job, Clock::time_point now = Clock::now()) {
    Queue& queue = queues_[session];
    // Refill the session's token bucket for the time since its last request.
    if (queue.last_refill == Clock::time_point{}) {
      queue.tokens = limits_.burst_per_session;
    } else {
      const double seconds = std::chrono::duration<double>(now - queue.last_refill).count();
      queue.tokens = std::min(limits_.burst_per_session,
                              queue.tokens + seconds * limits_.max_rate_per_session);
    }
    queue.last_refill = now;
    if (queue.tokens < 1.0) {
      return MakeError(ErrorCode::kBusy, "session is over its request rate (" +
                                             std::to_string(limits_.max_rate_per_session) + "/s)");
    }
    if (queue.jobs.size() >= limits_.max_queued_per_session) {
      return MakeError(ErrorCode::kBusy, "session has " + std::to_string(queue.jobs.size()) +
                                             " requests pending (limit " +
                                             std::to_string(limits_.max_queued_per_session) + ")");
    }
    if (total_ >= limits_.max_queued_total) {
      return MakeError(ErrorCode::kBusy,
                       "daemon has " + std::to_string(total_) + " requests pending");
    }
    queue.tokens -= 1.0;
    queue.jobs.push_back(std::move(job));
    ++total_;
    return {};
  }

  /// Takes the next job: the oldest of the first session after the one served last that has
  /// any (round-robin by session id). nullopt when nothing is queued.
  std::optional<std::pair<int64_t, Job>> Pop() {
    if (total_ == 0) return std::nullopt;
    auto it = queues_.upper_bound(last_served_);
    for (size_t i = 0; i <= queues_.size(); ++i, ++it) {
      if (it == queues_.end()) it = queues_.begin();
      if (!it->second.jobs.empty()) {
        Job job = std::move(it->second.jobs.front());
        it->second.jobs.pop_front();
        --total_;
        last_served_ = it->first;
        return std::make_pair(it->first, std::move(job));
      }
    }
    return std::nullopt;
  }

  /// Drops a session and its pending jobs; returns them so the caller can answer them.
  std::deque<Job> RemoveSession(int64_t session) {
    std::deque<Job> jobs;
    auto it = queues_.find(session);
    if (it != queues_.end()) {
      jobs = std::move(it->second.jobs);
      total_ -= jobs.size();
      queues_.erase(it);
    }
    return jobs;
  }

  size_t size() const { return total_; }
  size_t size(int64_t session) const {
    auto it = queues_.find(session);
    return it == queues_.end() ? 0 : it->second.jobs.size();
  }

 private:
  struct Queue {
    std::deque<Job> jobs;
    double tokens = 0;
    Clock::time_point last_refill{};
  };
  SchedulerLimits limits_;
  std::map<int64_t, Queue> queues_;
  size_t total_ = 0;
  int64_t last_served_ = -1;
};

}  // namespace far::server
