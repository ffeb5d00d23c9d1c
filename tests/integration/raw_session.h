#pragma once

// A hand-made session for the bad-input tests: it speaks the protocol through far::protocol
// directly (not through far::client), so a test can send exactly the bytes it wants (truncated,
// garbage, wrong version, forged tags, replays) and write raw records into the update ring.
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

#include "far/model/result.h"
#include "far/model/step_request.h"
#include "far/protocol/lcm_bus.h"
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

/// A decoded message of the session reply channel.
struct ReplyMessage {
  protocol::MessageType type = protocol::MessageType::kError;
  bool signed_ok = false;  ///< the tag verifies with the session key
  bool from_shm = false;   ///< a step reply that came as a stub, read from the reply ring
  std::optional<far_lcm::error_t> error;
  std::optional<far_lcm::step_reply_t> step;  ///< the full reply (ring fetched for stubs)
  std::optional<far_lcm::heartbeat_t> heartbeat;
};

/// A session opened by hand. Owns a Listener on FAR_OPEN_REPLY_<random> and FAR_S.*_REPLY.
class RawSession {
 public:
  /// Publishes an open_session_t (name, default rings) and maps the segment.
  /// Errors: kTimeout (no reply), the daemon's refusal, ShmSegment::Open's errors.
  static Result<std::unique_ptr<RawSession>> Open(
      const std::string& url, const std::string& name,
      std::chrono::milliseconds timeout = std::chrono::seconds(5));
  ~RawSession();

  int64_t id() const { return id_; }
  const std::string& shm_name() const { return segment_->name(); }
  const protocol::SessionKey& key() const { return key_; }
  std::string request_channel() const;
  std::string reply_channel() const;
  protocol::ShmSegment& segment() { return *segment_; }
  protocol::UpdateWriter& writer() { return *writer_; }
  Listener& listener() { return *listener_; }
  /// The client side of the reply ring (Decode reads stubs' replies with it).
  protocol::RingReader& reply_reader() { return *replies_; }

  /// The next request id (strictly increasing; each call takes one).
  int64_t NextRequestId() { return next_request_id_++; }

  /// Publishes bytes on this session's request channel.
  Result<void> PublishRequest(std::span<const uint8_t> bytes);
  /// Signs (with `key`, default the session key) and publishes a step request for `step_id`
  /// committing the ring up to `commit` (default: the writer's last sequence). Returns the
  /// request id it used.
  Result<int64_t> SendStep(int64_t step_id, const StepRequest& request,
                           std::optional<uint64_t> commit = std::nullopt,
                           const protocol::SessionKey* key = nullptr);
  /// Sends a signed heartbeat.
  Result<void> SendHeartbeat();

  /// Waits for a message on the session reply channel that `match` accepts (after decoding:
  /// step replies are fetched from the reply ring when they are stubs).
  std::optional<ReplyMessage> WaitReply(
      const std::function<bool(const ReplyMessage&)>& match,
      std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// The step_reply_t for `step_id` (signed), or nullopt.
  std::optional<far_lcm::step_reply_t> WaitStepReply(
      int64_t step_id, std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// The first error_t on the reply channel with this request_id (signed or not), or nullopt.
  std::optional<ReplyMessage> WaitError(
      int64_t request_id, std::chrono::milliseconds timeout = std::chrono::seconds(10));

  /// Decodes one reply channel message. Returns nullopt for bytes that do not decode.
  std::optional<ReplyMessage> Decode(const Received& message);

 private:
  RawSession() = default;
  std::unique_ptr<Listener> listener_;
  int64_t id_ = 0;
  std::unique_ptr<protocol::ShmSegment> segment_;
  protocol::SessionKey key_{};
  std::unique_ptr<protocol::UpdateWriter> writer_;
  std::unique_ptr<protocol::RingReader> replies_;
  std::deque<ReplyMessage> decoded_;  // decoded replies no WaitReply has taken yet
  int64_t next_request_id_ = 1;
};

/// Decodes an error_t without checking its tag. nullopt when it does not decode.
std::optional<far_lcm::error_t> DecodeError(std::span<const uint8_t> bytes);

/// A small step request: FAR, id buffer, resolution 128, contacts.
StepRequest SmallRequest(Method method = Method::kFar);

/// Makes an open_session_t for `reply_channel`.
far_lcm::open_session_t MakeOpenSession(const std::string& reply_channel, const std::string& name);

/// "FAR_OPEN_REPLY_" + 24 random hex digits.
std::string RandomOpenReplyChannel();

}  // namespace far::integration
