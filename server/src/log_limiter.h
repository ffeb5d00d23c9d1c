#pragma once

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rate_limiter.h"
#include <spdlog/spdlog.h>

namespace far::server {

/// How much a LogLimiter lets through.
struct LogPolicy {
  double lines_per_second = 1;  ///< sustained, per (user, kind)
  double burst = 20;            ///< lines at once after a quiet while
  std::chrono::seconds summary_period{10};
};

/// Holds what clients can make the daemon log to a few lines per second: a token bucket per
/// (user, kind) of line, and for the lines it held back, one summary per (user, kind) every
/// `summary_period` with their count ("event=log_suppressed kind=step_busy user=1001
/// count=41872 seconds=10"). A kind is an event name ("open_refused"), or "step_<code>" for
/// step errors. Lines of the daemon's own life (ready, stopping) do not go through it.
/// Thread-safe.
class LogLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  /// No uid known (a message from LCM before it is authenticated): counted as one more user.
  static constexpr uid_t kNoUser = static_cast<uid_t>(-1);

  using Policy = LogPolicy;
  /// The lines of one (user, kind) held back since `seconds` ago.
  struct Summary {
    uid_t uid = kNoUser;
    std::string kind;
    int64_t count = 0;
    double seconds = 0;
  };
  using SummarySink = std::function<void(const Summary&)>;

  /// Writes summaries to `sink` (by default LogSummary: spdlog, level warn).
  explicit LogLimiter(Policy policy = Policy(), SummarySink sink = LogSummary);

  /// Whether a line of `kind` about `uid` may be written now. When not, it is counted for
  /// the next summary. Writes the summary of this (uid, kind) when one is due.
  bool Allow(uid_t uid, std::string_view kind, Clock::time_point now = Clock::now());
  /// Writes the summaries that are due (all of them with `all`, at shutdown) and forgets
  /// (user, kind) pairs whose bucket has refilled. The daemon calls it at least once a
  /// second; it does the work at most once a second unless `all`.
  void Flush(Clock::time_point now = Clock::now(), bool all = false);
  /// How many (user, kind) pairs it tracks now.
  size_t tracked() const;

  /// The summary as the daemon logs it.
  static void LogSummary(const Summary& summary);

 private:
  struct Key {
    uid_t uid;
    std::string kind;
  };
  struct KeyView {
    uid_t uid;
    std::string_view kind;
  };
  struct KeyLess {
    using is_transparent = void;
    template <typename A, typename B>
    bool operator()(const A& a, const B& b) const {
      if (a.uid != b.uid) return a.uid < b.uid;
      return std::string_view(a.kind) < std::string_view(b.kind);
    }
  };
  struct Entry {
    RateLimiter bucket;
    int64_t held_back = 0;
    Clock::time_point first_held{};  ///< of the lines held back since the last summary
    Clock::time_point last_seen{};
  };
  // Takes the summary of `entry` when it is due (or with `all`); nullopt-like count 0 if not.
  Summary TakeSummary(const Key& key, Entry& entry, Clock::time_point now, bool all) const;
  void Write(const std::vector<Summary>& summaries) const;

  Policy policy_;
  SummarySink sink_;
  mutable std::mutex mutex_;
  std::map<Key, Entry, KeyLess> entries_;
  std::atomic<Clock::rep> next_flush_{0};
};

/// The daemon's limiter of lines that clients can cause.
LogLimiter& ClientLogLimiter();

/// Logs one line that a client can cause, through ClientLogLimiter(): about user `uid`, of
/// `kind`. Costs nothing more than spdlog's level check when `level` is not logged.
template <typename... Args>
void LogForClient(spdlog::level::level_enum level, uid_t uid, std::string_view kind,
                  spdlog::format_string_t<Args...> format, Args&&... args) {
  if (!spdlog::should_log(level) || !ClientLogLimiter().Allow(uid, kind)) return;
  spdlog::log(level, format, std::forward<Args>(args)...);
}

}  // namespace far::server
