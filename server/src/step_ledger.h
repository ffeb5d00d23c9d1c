#pragma once

// What a session remembers of its steps, so that a step request sent again (the request, or
// the daemon's answer to it, was lost on LCM) is answered from memory and never runs twice:
// requests are idempotent by step id (docs/protocol.md, "Lost datagrams").

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "far/base/stage.h"

namespace far::server {

struct StepJob;

/// What the daemon knows of a step a client asks for again.
struct StepRecall {
  enum class Kind {
    kAnswered,   ///< its answer is kept: `reply` is sent again
    kRunning,    ///< the worker runs it (in `stage`, or just started)
    kQueued,     ///< it waits in the session's queue at `queue_position`
    kForgotten,  ///< answered long ago: its answer is no longer kept
  };
  Kind kind = Kind::kForgotten;
  std::vector<uint8_t> reply;  ///< kAnswered: the encoding that went inside the sealed_t
  int64_t request_id = 0;      ///< kRunning, kQueued: the request that brought it
  std::optional<Stage> stage;  ///< kRunning: the stage it is in (none: started)
  int32_t queue_position = 0;  ///< kQueued: steps of the session ahead of it
  std::chrono::steady_clock::time_point received;  ///< kRunning, kQueued
};

/// A session's steps by id: the highest id taken, the step running now, and the answers to the
/// last few steps (the encodings that went inside their sealed_t: an inline reply, a stub
/// naming a record of the reply ring, or an error). Not thread-safe: the session's `mutex`
/// guards it, with the queue.
class StepLedger {
 public:
  /// Answers kept: at most this many, and this many bytes beyond the newest (kept always).
  static constexpr size_t kMaxKept = 4;
  static constexpr size_t kMaxKeptBytes = size_t{128} << 10;

  /// True when `step_id` is new (above every step id taken so far), which it then takes; false
  /// for a repeat. A negative id is never taken (the request is invalid and answered so).
  bool Take(int64_t step_id);
  /// The worker starts a step it took from the queue.
  void Start(int64_t step_id, int64_t request_id, std::chrono::steady_clock::time_point received);
  /// The running step enters `stage`.
  void EnterStage(Stage stage);
  /// Keeps the answer to `step_id` (dropping the oldest beyond the bounds); when it is the
  /// running step, that step is over.
  void Keep(int64_t step_id, std::vector<uint8_t> reply);
  /// The running step is over (answered or not).
  void Finish();
  /// What is known of `step_id`, a repeat (Take said false), given the session's queue.
  StepRecall Recall(int64_t step_id, const std::deque<StepJob>& queue) const;

  /// True while the worker runs a step (between Start and its answer or Finish).
  bool running() const { return running_.has_value(); }
  size_t kept_bytes() const { return kept_bytes_; }

 private:
  struct Running {
    int64_t step_id = 0, request_id = 0;
    std::chrono::steady_clock::time_point received;
    std::optional<Stage> stage;
  };
  struct Kept {
    int64_t step_id = 0;
    std::vector<uint8_t> reply;
  };
  int64_t last_step_id_ = -1;
  std::optional<Running> running_;
  std::deque<Kept> kept_;  // oldest first
  size_t kept_bytes_ = 0;
};

}  // namespace far::server
