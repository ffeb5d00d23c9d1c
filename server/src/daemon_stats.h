#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

#include "latency_stats.h"
#include <spdlog/spdlog.h>

namespace far::server {

/// The daemon-wide counters its status reports. Thread-safe.
class DaemonStats {
 public:
  /// Counts one error of `kind` (an ErrorCode name: "invalid_argument", "internal", ...).
  void CountError(const std::string& kind) {
    std::lock_guard lock(mutex_);
    errors_by_kind_[kind]++;
    errors_total_++;
  }
  /// Counts one message dropped unanswered before it reached a session (undecodable, not
  /// authenticated, replayed, for no session): an error of its kind and one more rejected
  /// message. Nobody is answered, and the log gets at most one line per kind every
  /// kDropLogPeriod, with the count since the last one: a flood costs a counter, not a reply
  /// and a log line per message.
  void CountRejected(const std::string& kind, std::string_view example = {}) {
    std::lock_guard lock(mutex_);
    errors_by_kind_[kind]++;
    errors_total_++;
    rejected_total_++;
    DropLog& log = drop_logs_[kind];
    log.unlogged++;
    const auto now = std::chrono::steady_clock::now();
    if (log.last != std::chrono::steady_clock::time_point{} && now - log.last < kDropLogPeriod)
      return;
    spdlog::warn("event=messages_dropped kind={} count={} example=\"{}\"", kind, log.unlogged,
                 example);
    log.unlogged = 0;
    log.last = now;
  }
  static constexpr std::chrono::seconds kDropLogPeriod{10};
  /// Counts one step served in `ms` (request received to reply ready; counted before it goes
  /// out) by `method`, the method that ran ("bvh", "gpu", "far", ...; StepStats::method up to
  /// its first '/').
  void CountStep(double ms, std::string_view method) {
    std::lock_guard lock(mutex_);
    latency_.Add(ms);
    steps_total_++;
    steps_by_method_[std::string(method.substr(0, method.find('/')))]++;
  }
  /// Counts one session open refused (limits, rate, bad parameters); its error kind is counted
  /// by CountError.
  void CountRefusedOpen() {
    std::lock_guard lock(mutex_);
    opens_refused_total_++;
  }

  struct Snapshot {
    std::map<std::string, int64_t> errors_by_kind, steps_by_method;
    int64_t errors_total = 0, rejected_total = 0, steps_total = 0, latency_samples = 0;
    int64_t opens_refused_total = 0;
    double p50_ms = 0, p90_ms = 0, p99_ms = 0, max_ms = 0;
  };
  Snapshot Read() const {
    std::lock_guard lock(mutex_);
    Snapshot snapshot;
    snapshot.errors_by_kind = errors_by_kind_;
    snapshot.steps_by_method = steps_by_method_;
    snapshot.opens_refused_total = opens_refused_total_;
    snapshot.errors_total = errors_total_;
    snapshot.rejected_total = rejected_total_;
    snapshot.steps_total = steps_total_;
    snapshot.latency_samples = static_cast<int64_t>(latency_.count());
    snapshot.p50_ms = latency_.Quantile(0.5);
    snapshot.p90_ms = latency_.Quantile(0.9);
    snapshot.p99_ms = latency_.Quantile(0.99);
    snapshot.max_ms = latency_.Quantile(1.0);
    return snapshot;
  }
  int64_t steps_total() const {
    std::lock_guard lock(mutex_);
    return steps_total_;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> errors_by_kind_, steps_by_method_;
  int64_t errors_total_ = 0;
  int64_t opens_refused_total_ = 0;
  int64_t rejected_total_ = 0;
  int64_t steps_total_ = 0;
  LatencyWindow latency_{8192};
  struct DropLog {
    int64_t unlogged = 0;
    std::chrono::steady_clock::time_point last{};
  };
  std::map<std::string, DropLog> drop_logs_;
};

}  // namespace far::server
