#include "raw_session.h"

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/version.h"

namespace far::integration {

using Clock = std::chrono::steady_clock;
using protocol::MessageType;

// ---- Listener ------------------------------------------------------------------------------

Result<std::unique_ptr<Listener>> Listener::Create(const std::string& url) {
  auto bus = protocol::LcmBus::Create(url);
  if (!bus) return bus.error();
  std::unique_ptr<Listener> listener(new Listener());
  listener->bus_ = std::move(*bus);
  return listener;
}

Listener::~Listener() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void Listener::Subscribe(const std::string& channel_regex) {
  bus_->Subscribe(channel_regex, [this](std::string_view channel, std::span<const uint8_t> bytes) {
    std::lock_guard lock(mutex_);
    received_.push_back({std::string(channel), std::vector<uint8_t>(bytes.begin(), bytes.end())});
    changed_.notify_all();
  });
}

void Listener::Start() {
  thread_ = std::thread([this] {
    while (!stop_) bus_->Handle(std::chrono::milliseconds(50));
  });
}

Result<void> Listener::Publish(const std::string& channel, std::span<const uint8_t> bytes) {
  return bus_->Publish(channel, bytes);
}

std::optional<Received> Listener::WaitFor(const std::function<bool(const Received&)>& match,
                                          std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  std::optional<Received> found;
  changed_.wait_for(lock, timeout, [&] {
    for (auto it = received_.begin(); it != received_.end(); ++it) {
      if (match(*it)) {
        found = std::move(*it);
        received_.erase(it);
        return true;
      }
    }
    return false;
  });
  return found;
}

void Listener::Clear() {
  std::lock_guard lock(mutex_);
  received_.clear();
}

std::vector<Received> Listener::Snapshot() {
  std::lock_guard lock(mutex_);
  return received_;
}

// ---- helpers -------------------------------------------------------------------------------

std::optional<far_lcm::error_t> DecodeError(std::span<const uint8_t> bytes) {
  auto error = protocol::DecodeMessage<far_lcm::error_t>(bytes.data(), bytes.size(),
                                                         protocol::kMaxControlMessageBytes);
  if (!error) return std::nullopt;
  return *error;
}

StepRequest SmallRequest(Method method) {
  StepRequest request;
  request.method = method;
  request.mechanism = QueryMechanism::kIdBuffer;
  request.resolution = 128;
  request.output = Output::kContacts;
  return request;
}

far_lcm::open_session_t MakeOpenSession(const std::string& reply_channel, const std::string& name) {
  far_lcm::open_session_t open{};
  open.protocol_version = protocol::kProtocolVersion;
  int64_t id = 0;
  protocol::RandomBytes(reinterpret_cast<uint8_t*>(&id), sizeof(id));
  open.request_id = id & 0x3fffffffffffffff;
  open.client_name = name;
  open.reply_channel = reply_channel;
  open.update_ring_bytes = 0;
  open.reply_ring_bytes = 0;
  return open;
}

std::string RandomOpenReplyChannel() {
  uint8_t random[12];
  protocol::RandomBytes(random, sizeof(random));
  static const char* kDigits = "0123456789abcdef";
  std::string channel(protocol::kOpenReplyPrefix);
  for (uint8_t b : random) {
    channel += kDigits[b >> 4];
    channel += kDigits[b & 15];
  }
  return channel;
}

// ---- RawSession ----------------------------------------------------------------------------

Result<std::unique_ptr<RawSession>> RawSession::Open(const std::string& url,
                                                     const std::string& name,
                                                     std::chrono::milliseconds timeout) {
  std::unique_ptr<RawSession> session(new RawSession());
  auto listener = Listener::Create(url);
  if (!listener) return listener.error();
  session->listener_ = std::move(*listener);
  const std::string open_channel = RandomOpenReplyChannel();
  session->listener_->Subscribe(open_channel);
  session->listener_->Subscribe("FAR_S[0-9]+_REPLY");
  session->listener_->Start();

  const far_lcm::open_session_t open = MakeOpenSession(open_channel, name);
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes) return bytes.error();
  if (auto sent = session->listener_->Publish(std::string(protocol::kOpenChannel), *bytes); !sent) {
    return sent.error();
  }
  auto got = session->listener_->WaitFor(
      [&](const Received& r) { return r.channel == open_channel; }, timeout);
  if (!got)
    return MakeError(ErrorCode::kTimeout,
                     "no open_session_reply_t within " + std::to_string(timeout.count()) + " ms");
  auto reply = protocol::DecodeMessage<far_lcm::open_session_reply_t>(
      got->bytes.data(), got->bytes.size(), protocol::kMaxControlMessageBytes);
  if (!reply) return reply.error();
  if (reply->status != protocol::kWireOk) {
    return MakeError(protocol::FromWireStatus(reply->status), "open refused: " + reply->message);
  }
  auto segment =
      protocol::ShmSegment::Open(reply->shm_name, static_cast<uint64_t>(reply->session_id));
  if (!segment) return segment.error();
  session->id_ = reply->session_id;
  session->segment_ = std::move(*segment);
  session->key_ = session->segment_->session_key();
  session->writer_ = std::make_unique<protocol::UpdateWriter>(session->segment_->update_ring());
  session->replies_ = std::make_unique<protocol::RingReader>(
      session->segment_->reply_ring(), session->segment_->layout().reply_ring_capacity);
  return session;
}

RawSession::~RawSession() {
  // The listener's thread stops before the segment is unmapped.
  listener_.reset();
}

std::string RawSession::request_channel() const { return protocol::SessionRequestChannel(id_); }
std::string RawSession::reply_channel() const { return protocol::SessionReplyChannel(id_); }

Result<void> RawSession::PublishRequest(std::span<const uint8_t> bytes) {
  return listener_->Publish(request_channel(), bytes);
}

Result<int64_t> RawSession::SendStep(int64_t step_id, const StepRequest& request,
                                     std::optional<uint64_t> commit,
                                     const protocol::SessionKey* key) {
  const int64_t request_id = NextRequestId();
  auto message = protocol::MakeStepRequest(id_, request_id, step_id,
                                           commit.value_or(writer_->last_sequence()), request);
  auto bytes = protocol::EncodeSigned(message, key != nullptr ? *key : key_);
  if (!bytes) return bytes.error();
  if (auto sent = PublishRequest(*bytes); !sent) return sent.error();
  return request_id;
}

Result<void> RawSession::SendHeartbeat() {
  far_lcm::heartbeat_t heartbeat{};
  heartbeat.protocol_version = protocol::kProtocolVersion;
  heartbeat.session_id = id_;
  heartbeat.request_id = NextRequestId();
  auto bytes = protocol::EncodeSigned(heartbeat, key_);
  if (!bytes) return bytes.error();
  return PublishRequest(*bytes);
}

std::optional<ReplyMessage> RawSession::Decode(const Received& message) {
  auto type = protocol::IdentifyMessage(message.bytes.data(), message.bytes.size());
  if (!type) return std::nullopt;
  ReplyMessage decoded;
  decoded.type = *type;
  const std::span<const uint8_t> bytes(message.bytes);
  switch (*type) {
    case MessageType::kStepReply: {
      auto full = protocol::ReceiveStepReply(bytes.data(), bytes.size(), key_, *replies_);
      if (full) {
        auto stub = protocol::DecodeMessage<far_lcm::step_reply_t>(bytes.data(), bytes.size(),
                                                                   protocol::kMaxStepReplyBytes);
        decoded.from_shm = stub.ok() && stub->reply_in_shm;
        decoded.signed_ok = true;
        decoded.step = std::move(*full);
      } else {
        auto plain = protocol::DecodeMessage<far_lcm::step_reply_t>(bytes.data(), bytes.size(),
                                                                    protocol::kMaxStepReplyBytes);
        if (!plain) return std::nullopt;
        decoded.step = std::move(*plain);
      }
      return decoded;
    }
    case MessageType::kError: {
      decoded.error = DecodeError(bytes);
      if (!decoded.error) return std::nullopt;
      decoded.signed_ok = protocol::VerifyEncoded(bytes, key_).ok();
      return decoded;
    }
    case MessageType::kHeartbeat: {
      auto heartbeat = protocol::DecodeMessage<far_lcm::heartbeat_t>(
          bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
      if (!heartbeat) return std::nullopt;
      decoded.heartbeat = std::move(*heartbeat);
      decoded.signed_ok = protocol::VerifyEncoded(bytes, key_).ok();
      return decoded;
    }
    default:
      return decoded;
  }
}

std::optional<ReplyMessage> RawSession::WaitReply(
    const std::function<bool(const ReplyMessage&)>& match, std::chrono::milliseconds timeout) {
  // Replies decoded earlier by another wait come first, in arrival order.
  for (auto it = decoded_.begin(); it != decoded_.end(); ++it) {
    if (match(*it)) {
      ReplyMessage found = std::move(*it);
      decoded_.erase(it);
      return found;
    }
  }
  const auto deadline = Clock::now() + timeout;
  const std::string channel = reply_channel();
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return std::nullopt;
    auto got = listener_->WaitFor([&](const Received& r) { return r.channel == channel; }, left);
    if (!got) return std::nullopt;
    auto decoded = Decode(*got);
    if (!decoded) continue;
    if (match(*decoded)) return decoded;
    decoded_.push_back(std::move(*decoded));
  }
}

std::optional<far_lcm::step_reply_t> RawSession::WaitStepReply(int64_t step_id,
                                                               std::chrono::milliseconds timeout) {
  auto reply = WaitReply(
      [&](const ReplyMessage& m) { return m.step && m.signed_ok && m.step->step_id == step_id; },
      timeout);
  if (!reply) return std::nullopt;
  return reply->step;
}

std::optional<ReplyMessage> RawSession::WaitError(int64_t request_id,
                                                  std::chrono::milliseconds timeout) {
  return WaitReply(
      [&](const ReplyMessage& m) { return m.error && m.error->request_id == request_id; }, timeout);
}

}  // namespace far::integration
