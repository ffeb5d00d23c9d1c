#pragma once

// A hand-made session for the bad-input tests: it speaks the protocol through far::protocol
// directly (not through far::client), so a test can send exactly the bytes it wants (truncated,
// garbage, wrong version, forged tags, replays), write raw records into the update ring, and
// drop its connection to the daemon as a crashing client would.
//
// Listener: an LCM bus of its own with a receive thread that keeps every message of the
// channels it subscribed to, so a test can wait for "the error_t about request 7" and decode it.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "far/base/result.h"
#include "far/model/step_request.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message.h"
#include "far/protocol/ring.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_segment.h"

namespace far::integration {

/// One received LCM message.
struct Received {
  std::string channel;
  std::vector<uint8_t> bytes;
};

/// An LCM bus that records what arrives on the subscribed channels. Subscribe before Start.
class Listener {
 public:
  static Result<std::unique_ptr<Listener>> Create(const std::string& url);
  ~Listener();

  /// Subscribes (LCM regular expression); only before Start.
  void Subscribe(const std::string& channel_regex);
  /// Starts the receive thread.
  void Start();
  /// Publishes raw bytes.
  Result<void> Publish(const std::string& channel, std::span<const uint8_t> bytes);
  /// Waits for the first message (received since the last Clear and not yet taken) that
  /// `match` accepts, removes it and returns it; nullopt after `timeout`.
  std::optional<Received> WaitFor(const std::function<bool(const Received&)>& match,
                                  std::chrono::milliseconds timeout);
  /// Forgets every message received so far.
  void Clear();
  /// Copies of the messages received so far (not taken).
  std::vector<Received> Snapshot();

 private:
  Listener() = default;
  std::unique_ptr<protocol::LcmBus> bus_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Received> received_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// A decoded message of the session reply channel: a sealed_t opened with the session key.
struct ReplyMessage {
  protocol::MessageType type = protocol::MessageType::kError;  ///< of the inner message
  int64_t sequence = 0;   ///< sealed_t.request_id: the daemon's sequence
  bool from_shm = false;  ///< a step reply that came as a stub, read from the reply ring
  std::optional<far_lcm::error_t> error;
  std::optional<far_lcm::step_reply_t> step;  ///< the full reply (ring fetched for stubs)
  std::optional<far_lcm::step_status_t> status;
};

/// A session opened by hand: a connection to the daemon's socket (the session lives as long as
/// it does), the mapped segment, and a Listener on the session's reply channel.
class RawSession {
 public:
  /// Connects to the daemon's socket, sends an open_session_t (name, default rings), maps the
  /// segment that comes back and listens on `lcm_url`. Errors: kTimeout (no reply), the
  /// daemon's refusal, ShmSegment::Open's errors.
  static Result<std::unique_ptr<RawSession>> Open(
      const std::string& socket_path, const std::string& lcm_url, const std::string& name,
      std::chrono::milliseconds timeout = std::chrono::seconds(5));
  ~RawSession();

  int64_t id() const { return id_; }
  const protocol::SessionKey& key() const { return key_; }
  const std::string& request_channel() const { return request_channel_; }
  const std::string& reply_channel() const { return reply_channel_; }
  protocol::ShmSegment& segment() { return *segment_; }
  protocol::UpdateWriter& writer() { return *writer_; }
  Listener& listener() { return *listener_; }
  /// The client side of the reply ring (Decode reads stubs' replies with it).
  protocol::RingReader& reply_reader() { return *replies_; }
  /// Closes the connection to the daemon, as a client that exits or crashes does.
  void Disconnect() { connection_.reset(); }
  /// A descriptor of the segment (kept for hostile tests: a real client needs none).
  int segment_fd() const { return segment_fd_; }

  /// The next request id (strictly increasing; each call takes one).
  int64_t NextRequestId() { return next_request_id_++; }

  /// Publishes bytes on this session's request channel.
  Result<void> PublishRequest(std::span<const uint8_t> bytes);
  /// Signs (with `key`, default the session key) and publishes a step request for `step_id`
  /// committing the ring up to `commit` (default: the writer's last sequence). Returns the
  /// request id it used.
  Result<int64_t> SendStep(int64_t step_id, const StepRequest& request,
                           std::optional<uint64_t> commit = std::nullopt,
                           const protocol::SessionKey* key = nullptr, int32_t timeout_ms = 0);

  /// Waits for a message on the session reply channel that `match` accepts (after opening and
  /// decoding: step replies are fetched from the reply ring when they are stubs).
  std::optional<ReplyMessage> WaitReply(
      const std::function<bool(const ReplyMessage&)>& match,
      std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// The step_reply_t for `step_id`, or nullopt.
  std::optional<far_lcm::step_reply_t> WaitStepReply(
      int64_t step_id, std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// The first error_t on the reply channel with this request_id, or nullopt.
  std::optional<ReplyMessage> WaitError(
      int64_t request_id, std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// Every message that arrived on the reply channel so far, opened or not (raw).
  std::vector<Received> RawReplies() { return listener_->Snapshot(); }

  /// Opens one reply channel message. nullopt for bytes that do not open with the session key
  /// or do not decode.
  std::optional<ReplyMessage> Decode(const Received& message);

 private:
  RawSession() = default;
  std::unique_ptr<protocol::LocalConnection> connection_;
  std::unique_ptr<Listener> listener_;
  int64_t id_ = 0;
  std::string request_channel_, reply_channel_;
  std::unique_ptr<protocol::ShmSegment> segment_;
  int segment_fd_ = -1;
  protocol::SessionKey key_{};
  std::unique_ptr<protocol::UpdateWriter> writer_;
  std::unique_ptr<protocol::RingReader> replies_;
  std::deque<ReplyMessage> decoded_;  // decoded replies no WaitReply has taken yet
  int64_t next_request_id_ = 1;
};

/// Connects to the daemon's socket, sends `bytes` as the first message and returns the
/// daemon's answer (an encoded message; a descriptor that came with it is closed). Errors:
/// kUnavailable when the daemon closed the connection without answering, kTimeout.
Result<std::vector<uint8_t>> AskDaemon(const std::string& socket_path,
                                       std::span<const uint8_t> bytes,
                                       std::chrono::milliseconds timeout = std::chrono::seconds(5));

/// A small step request: FAR, id buffer, resolution 128, contacts.
StepRequest SmallRequest(Method method = Method::kFar);

/// Makes an open_session_t.
far_lcm::open_session_t MakeOpenSession(const std::string& name);

}  // namespace far::integration
