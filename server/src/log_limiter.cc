#include "log_limiter.h"

#include <cmath>

namespace far::server {

LogLimiter::LogLimiter(Policy policy, SummarySink sink) : policy_(policy), sink_(std::move(sink)) {}

bool LogLimiter::Allow(uid_t uid, std::string_view kind, Clock::time_point now) {
  std::vector<Summary> due;
  bool allowed = false;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(KeyView{uid, kind});
    if (it == entries_.end()) {
      it = entries_
               .emplace(Key{uid, std::string(kind)},
                        Entry{RateLimiter(policy_.lines_per_second, policy_.burst)})
               .first;
    }
    Entry& entry = it->second;
    entry.last_seen = now;
    allowed = entry.bucket.Allow(now);
    if (!allowed && entry.held_back++ == 0) entry.first_held = now;
    // A flood that goes on is summarized on time without waiting for Flush.
    if (Summary summary = TakeSummary(it->first, entry, now, false); summary.count > 0)
      due.push_back(std::move(summary));
  }
  Write(due);
  return allowed;
}

void LogLimiter::Flush(Clock::time_point now, bool all) {
  const Clock::rep ticks = now.time_since_epoch().count();
  if (!all && ticks < next_flush_.load(std::memory_order_relaxed)) return;
  next_flush_.store((now + std::chrono::seconds(1)).time_since_epoch().count(),
                    std::memory_order_relaxed);
  // A pair whose bucket is full again has nothing to remember.
  const auto refill = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(policy_.burst / policy_.lines_per_second));
  std::vector<Summary> due;
  {
    std::lock_guard lock(mutex_);
    for (auto it = entries_.begin(); it != entries_.end();) {
      if (Summary summary = TakeSummary(it->first, it->second, now, all); summary.count > 0)
        due.push_back(std::move(summary));
      if (it->second.held_back == 0 && now - it->second.last_seen >= refill) {
        it = entries_.erase(it);
      } else {
        ++it;
      }
    }
  }
  Write(due);
}

size_t LogLimiter::tracked() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

LogLimiter::Summary LogLimiter::TakeSummary(const Key& key, Entry& entry, Clock::time_point now,
                                            bool all) const {
  if (entry.held_back == 0) return {};
  if (!all && now - entry.first_held < policy_.summary_period) return {};
  Summary summary{key.uid, key.kind, entry.held_back,
                  std::chrono::duration<double>(now - entry.first_held).count()};
  entry.held_back = 0;
  return summary;
}

void LogLimiter::Write(const std::vector<Summary>& summaries) const {
  for (const Summary& summary : summaries) sink_(summary);
}

void LogLimiter::LogSummary(const Summary& summary) {
  const long long seconds = std::llround(summary.seconds);
  if (summary.uid == kNoUser) {
    spdlog::warn("event=log_suppressed kind={} user=unknown count={} seconds={}", summary.kind,
                 summary.count, seconds);
  } else {
    spdlog::warn("event=log_suppressed kind={} user={} count={} seconds={}", summary.kind,
                 summary.uid, summary.count, seconds);
  }
}

LogLimiter& ClientLogLimiter() {
  static LogLimiter limiter;
  return limiter;
}

}  // namespace far::server
