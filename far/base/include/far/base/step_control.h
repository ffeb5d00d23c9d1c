#pragma once

// What may end a step early, and what it tells its caller while it runs. A daemon serving many
// clients gives each step one: the client's cancellation (it closed its session or gave up),
// a deadline, and a cap on the pairs its reply may carry.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>

#include "far/base/stage.h"

namespace far {

/// Why a step or stage ended before its work was done.
enum class StopReason {
  kNone,       ///< it ran to the end
  kCancelled,  ///< the caller's cancel flag was set
  kDeadline,   ///< the deadline passed
  kPairLimit,  ///< it found more pairs (contacts + distance pairs) than max_pairs
};

/// Limits and signals of one step. Stages check them between their parts and, in the long
/// stages (exact tests, hierarchy descent, brute force, FCL), every few hundred triangle pairs,
/// so a stopped step ends within milliseconds. Default: nothing stops a step.
struct StepControl {
  using Clock = std::chrono::steady_clock;
  /// Set (by another thread) to abandon the step; read with relaxed loads.
  const std::atomic<bool>* cancel = nullptr;
  Clock::time_point deadline = Clock::time_point::max();
  /// The most contacts + distance pairs a step may report: a reply larger than this is refused
  /// while the pairs are found, not after they all are.
  size_t max_pairs = std::numeric_limits<size_t>::max();
  /// Called at the start of each stage, on the step's thread: progress for a client that waits.
  std::function<void(Stage stage)> on_stage;
  /// Called by every check (Check) from `slow_after` on, on the thread that checks: each
  /// thread working on a step that runs long hears it within milliseconds, which lets a daemon
  /// lower that thread's CPU priority while the step still runs, whether it ends well or not.
  /// Called again at every later check: it must be cheap once it has done its work.
  std::function<void()> on_slow;
  Clock::time_point slow_after = Clock::time_point::max();
  /// Called on the step's thread (the caller of Pipeline::Step) at the start and the end of
  /// each part of the step that later steps of the same scene do not repeat: the hierarchy
  /// builds and GPU pieces of new objects, a GL renderer's first step (shaders, framebuffers),
  /// and an `auto` step that tries a configuration or measures the GPU (the steps after it run
  /// the one chosen). A daemon accounts that work apart from the step's steady cost. Parts may
  /// nest; each begin has its end. Either may be empty.
  std::function<void()> on_setup_begin, on_setup_end;

  /// kCancelled or kDeadline when the step must stop now, else kNone (reads the clock; calls
  /// on_slow past slow_after).
  StopReason Check() const {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return StopReason::kCancelled;
    if (deadline == Clock::time_point::max() && slow_after == Clock::time_point::max())
      return StopReason::kNone;
    const Clock::time_point now = Clock::now();
    if (now >= slow_after && on_slow) on_slow();
    return now >= deadline ? StopReason::kDeadline : StopReason::kNone;
  }
};

/// The stop state the threads of one stage (or one long piece of work) share: the caller's
/// StepControl (cancel, deadline) and its cap on reported pairs. Threads poll it between parts
/// of their work (Poll reads the clock: every few hundred triangle pairs, every few thousand
/// triangles of a build) and add the pairs they found in batches; once stopped, every thread
/// returns at its next check. A null control never stops.
class StepStopper {
 public:
  explicit StepStopper(const StepControl* control) : control_(control) {}
  StepStopper(const StepStopper&) = delete;
  StepStopper& operator=(const StepStopper&) = delete;
  /// True once the stage must stop (an atomic load).
  bool stopped() const { return reason_.load(std::memory_order_relaxed) != 0; }
  /// Re-reads the cancel flag and the clock; true when the stage must stop.
  bool Poll() {
    if (stopped()) return true;
    if (control_ == nullptr) return false;
    const StopReason reason = control_->Check();
    if (reason != StopReason::kNone) Stop(reason);
    return reason != StopReason::kNone;
  }
  /// Adds `n` pairs one thread found; stops the stage once the total is over the cap.
  void AddFound(size_t n) {
    if (control_ == nullptr || n == 0) return;
    const size_t total = found_.fetch_add(n, std::memory_order_relaxed) + n;
    if (total > control_->max_pairs) Stop(StopReason::kPairLimit);
  }
  StopReason reason() const { return static_cast<StopReason>(reason_.load()); }

 private:
  void Stop(StopReason reason) {
    int none = 0;
    reason_.compare_exchange_strong(none, static_cast<int>(reason));
  }
  const StepControl* control_;
  std::atomic<size_t> found_{0};
  std::atomic<int> reason_{0};
};

/// Marks the work of a scope as setup (StepControl::on_setup_begin and on_setup_end), from its
/// construction to End() or its destruction, whichever comes first. A null control: nothing.
class SetupScope {
 public:
  explicit SetupScope(const StepControl* control) : control_(control) {
    if (control_ != nullptr && control_->on_setup_begin) control_->on_setup_begin();
  }
  SetupScope(const SetupScope&) = delete;
  SetupScope& operator=(const SetupScope&) = delete;
  ~SetupScope() { End(); }
  void End() {
    if (control_ != nullptr && control_->on_setup_end) control_->on_setup_end();
    control_ = nullptr;
  }

 private:
  const StepControl* control_;
};

}  // namespace far
