#pragma once

#include <time.h>

#include <algorithm>
#include <atomic>
#include <optional>

#include "setup_allowance.h"

namespace far::server {

/// A thread's CPU time in ms (its clock, which other threads can read too); 0 without one.
inline double ThreadCpuMs(std::optional<clockid_t> clock) {
  timespec t{};
  if (!clock || clock_gettime(*clock, &t) != 0) return 0;
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

/// A session worker's CPU time on one step (read from the worker's clock), with its setup
/// (StepControl::on_setup_begin/end: one-off work such as hierarchy builds) covered by the
/// user's SetupAllowance as far as it lasts: only the rest, the step's steady cost, can make
/// the step heavy. BeginSetup and EndSetup run on the worker; the rest on any thread.
class StepCpuMeter {
 public:
  StepCpuMeter(std::optional<clockid_t> clock, SetupAllowance& allowance, uid_t uid)
      : clock_(clock), allowance_(allowance), uid_(uid), started_ms_(ThreadCpuMs(clock)) {}

  void BeginSetup() {
    if (depth_++ == 0) open_since_ms_.store(ThreadCpuMs(clock_), std::memory_order_relaxed);
  }
  void EndSetup() {
    if (depth_ == 0 || --depth_ > 0) return;
    const double ms = ThreadCpuMs(clock_) - open_since_ms_.load(std::memory_order_relaxed);
    open_since_ms_.store(-1, std::memory_order_relaxed);
    setup_ms_.fetch_add(ms, std::memory_order_relaxed);
    covered_ms_.fetch_add(allowance_.TakeUpTo(uid_, ms), std::memory_order_relaxed);
  }

  /// CPU ms since the step started, less the setup covered so far (a part still running counts
  /// as covered as far as the allowance now holds).
  double SteadyMs() const {
    const double now = ThreadCpuMs(clock_);
    double covered = covered_ms_.load(std::memory_order_relaxed);
    if (const double since = open_since_ms_.load(std::memory_order_relaxed); since >= 0)
      covered += std::min(now - since, allowance_.Available(uid_));
    return now - started_ms_ - covered;
  }
  double setup_ms() const { return setup_ms_.load(std::memory_order_relaxed); }
  double covered_ms() const { return covered_ms_.load(std::memory_order_relaxed); }

 private:
  const std::optional<clockid_t> clock_;
  SetupAllowance& allowance_;
  const uid_t uid_;
  const double started_ms_;
  int depth_ = 0;                          // worker only: setup parts nest
  std::atomic<double> open_since_ms_{-1};  // CPU time the open part began at; -1: none open
  std::atomic<double> setup_ms_{0}, covered_ms_{0};
};

}  // namespace far::server
