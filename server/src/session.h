#pragma once

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "latency_stats.h"
#include "rate_limiter.h"
#include "step_ledger.h"

#include "far/pipeline/pipeline.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_segment.h"

namespace far::server {

using Clock = std::chrono::steady_clock;

/// A validated step request waiting for its session's worker.
struct StepJob {
  protocol::StepCommand command;
  Clock::time_point received;
  Clock::time_point deadline;  ///< received + min(the client's timeout, step_deadline_ms)
};

/// One client's session. Each group of fields is owned by the thread its comment names; the
/// queue is shared under `mutex`.
struct Session {
  // Set at open, then read-only:
  int64_t id = 0;
  uid_t uid = 0;
  pid_t pid = 0;
  std::string client_name;
  std::string request_channel, reply_channel;
  protocol::SessionKey key{};
  // LCM thread:
  int64_t last_request_id = -1;
  RateLimiter request_rate{1000, 50};
  /// Requests answered from memory (repeats of a step, probes), per second and in a burst: a
  /// client asks again at most every 200 ms per step it waits for, and one repeat may put a
  /// 63 KiB reply on the bus. Over it, repeats are dropped (counted) like a flood.
  static constexpr double kRepeatsPerSecond = 20;
  RateLimiter repeat_rate{kRepeatsPerSecond, kRepeatsPerSecond};
  // Worker thread (session_worker.h), which also frees them when the session ends:
  std::unique_ptr<protocol::ShmSegment> segment;
  std::unique_ptr<protocol::UpdateReader> updates;
  std::unique_ptr<protocol::RingWriter> replies;
  std::unique_ptr<Pipeline> pipeline;
  /// Runs at a lower CPU priority (a step of it ran longer than heavy_step_ms). Set by the
  /// worker or a pool thread of its pipeline while such a step runs.
  std::atomic<bool> demoted{false};
  std::thread worker;  ///< joined by the registry (ReapWorkers)
  // Shared under `mutex`:
  std::mutex mutex;
  std::condition_variable wake;
  std::deque<StepJob> queue;
  StepLedger ledger;  ///< its steps by id: the highest taken, the running one, the last answers
  bool closing = false;
  // Any thread:
  std::atomic<bool> cancel{false};  ///< the running step stops at its next check
  std::atomic<bool> worker_done{false};
  /// Taken for each sealed message from its sequence number to its publishing, so that the
  /// client, which drops a sequence number below one it has seen, gets them in that order.
  std::mutex publish_mutex;
  std::atomic<int64_t> next_reply_id{1};  ///< daemon -> client sequence (sealed_t.request_id)
  std::atomic<int64_t> steps{0};
  /// Idle expiry (session_idle_timeout_s): when a step of it was last queued, started or ended
  /// (at first, when it opened), and whether its worker is running one now.
  std::atomic<Clock::rep> last_active{0};
  std::atomic<bool> stepping{false};
  std::atomic<uint64_t> applied_sequence{0};
  std::atomic<int> num_objects{0};
  std::atomic<int64_t> num_triangles{0};
  std::mutex latency_mutex;
  LatencyWindow latency{1024};
};

/// Milliseconds between two times.
inline double MsBetween(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

}  // namespace far::server
