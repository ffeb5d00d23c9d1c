#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "latency_stats.h"

#include "far/pipeline/pipeline.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_segment.h"

namespace far::server {

/// One client's session. Each field is owned by the thread its group names.
struct Session {
  // Set at open, then read-only:
  int64_t id = 0;
  std::string client_name;
  std::string request_channel, reply_channel;
  protocol::SessionKey key{};
  std::unique_ptr<protocol::ShmSegment> segment;  // destroyed (and unlinked) on the GL thread
  // LCM thread:
  int64_t last_request_id = -1;
  // GL thread:
  std::unique_ptr<protocol::UpdateReader> updates;
  std::unique_ptr<protocol::RingWriter> replies;
  std::unique_ptr<Pipeline> pipeline;  // made on the first step, with the GL context current
  // Any thread:
  std::atomic<int64_t> last_heard_ms{0};
  std::atomic<int64_t> next_reply_id{1};  // daemon -> client request_id, strictly increasing
  std::atomic<int64_t> steps{0};
  std::atomic<int64_t> last_step_id{-1};
  std::atomic<uint64_t> applied_sequence{0};
  std::atomic<int> num_objects{0};
  std::mutex latency_mutex;
  LatencyWindow latency{1024};
};

/// A validated step request waiting for the GL thread.
struct StepJob {
  std::shared_ptr<Session> session;
  protocol::StepCommand command;
  std::chrono::steady_clock::time_point received;
};

/// Milliseconds on the steady clock (heartbeat bookkeeping).
inline int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace far::server
