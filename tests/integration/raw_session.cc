#include "raw_session.h"

#include <unistd.h>

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

StepRequest SmallRequest(Method method) {
  StepRequest request;
  request.method = method;
  request.mechanism = QueryMechanism::kIdBuffer;
  request.resolution = 128;
  request.output = Output::kContacts;
  return request;
}

far_lcm::open_session_t MakeOpenSession(const std::string& name) {
  far_lcm::open_session_t open{};
  open.protocol_version = protocol::kProtocolVersion;
  int64_t id = 0;
  protocol::RandomBytes(reinterpret_cast<uint8_t*>(&id), sizeof(id));
  open.request_id = id & 0x3fffffffffffffff;
  open.client_name = name;
  open.update_ring_bytes = 0;
  open.reply_ring_bytes = 0;
  return open;
}

Result<std::vector<uint8_t>> AskDaemon(const std::string& socket_path,
                                       std::span<const uint8_t> bytes,
                                       std::chrono::milliseconds timeout) {
  auto connection = protocol::LocalConnection::Connect(socket_path);
  if (!connection) return connection.error();
  if (auto sent = connection->Send(bytes); !sent) return sent.error();
  auto answer = connection->Receive(protocol::kMaxStatusReplyBytes, timeout, true);
  if (!answer) return answer.error();
  if (answer->fd >= 0) close(answer->fd);
  return std::move(answer->bytes);
}

// ---- RawSession ----------------------------------------------------------------------------

Result<std::unique_ptr<RawSession>> RawSession::Open(const std::string& socket_path,
                                                     const std::string& lcm_url,
                                                     const std::string& name,
                                                     std::chrono::milliseconds timeout) {
  std::unique_ptr<RawSession> session(new RawSession());
  auto connection = protocol::LocalConnection::Connect(socket_path);
  if (!connection) return connection.error();
  session->connection_ = std::make_unique<protocol::LocalConnection>(std::move(*connection));
  const far_lcm::open_session_t open = MakeOpenSession(name);
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes) return bytes.error();
  if (auto sent = session->connection_->Send(*bytes); !sent) return sent.error();
  auto answer = session->connection_->Receive(protocol::kMaxControlMessageBytes, timeout, true);
  if (!answer) return answer.error();
  auto reply = protocol::DecodeMessage<far_lcm::open_session_reply_t>(
      answer->bytes.data(), answer->bytes.size(), protocol::kMaxControlMessageBytes);
  if (!reply || reply->status != protocol::kWireOk) {
    if (answer->fd >= 0) close(answer->fd);
    if (!reply) return reply.error();
    return MakeError(protocol::FromWireStatus(reply->status), "open refused: " + reply->message);
  }
  session->segment_fd_ = dup(answer->fd);
  auto segment = protocol::ShmSegment::Open(answer->fd, static_cast<uint64_t>(reply->session_id));
  if (!segment) return segment.error();
  session->id_ = reply->session_id;
  session->request_channel_ = reply->request_channel;
  session->reply_channel_ = reply->session_reply_channel;
  session->segment_ = std::move(*segment);
  session->key_ = session->segment_->session_key();
  session->writer_ = std::make_unique<protocol::UpdateWriter>(session->segment_->update_ring());
  session->replies_ = std::make_unique<protocol::RingReader>(
      session->segment_->reply_ring(), session->segment_->layout().reply_ring_capacity);
  auto listener = Listener::Create(lcm_url);
  if (!listener) return listener.error();
  session->listener_ = std::move(*listener);
  session->listener_->Subscribe(session->reply_channel_);
  session->listener_->Start();
  return session;
}

RawSession::~RawSession() {
  // The listener's thread stops before the segment is unmapped.
  listener_.reset();
  if (segment_fd_ >= 0) close(segment_fd_);
}

Result<void> RawSession::PublishRequest(std::span<const uint8_t> bytes) {
  return listener_->Publish(request_channel_, bytes);
}

Result<int64_t> RawSession::SendStep(int64_t step_id, const StepRequest& request,
                                     std::optional<uint64_t> commit,
                                     const protocol::SessionKey* key, int32_t timeout_ms) {
  const int64_t request_id = NextRequestId();
  auto message = protocol::MakeStepRequest(
      id_, request_id, step_id, commit.value_or(writer_->last_sequence()), request, timeout_ms);
  auto bytes = protocol::EncodeSigned(message, key != nullptr ? *key : key_);
  if (!bytes) return bytes.error();
  if (auto sent = PublishRequest(*bytes); !sent) return sent.error();
  return request_id;
}

std::optional<ReplyMessage> RawSession::Decode(const Received& message) {
  auto opened = protocol::OpenSealed(message.bytes.data(), message.bytes.size(), id_, key_,
                                     protocol::kMaxStepReplyBytes);
  if (!opened) return std::nullopt;
  auto type = protocol::IdentifyMessage(opened->inner.data(), opened->inner.size());
  if (!type) return std::nullopt;
  ReplyMessage decoded;
  decoded.type = *type;
  decoded.sequence = opened->request_id;
  const std::span<const uint8_t> inner(opened->inner);
  switch (*type) {
    case MessageType::kStepReply: {
      auto stub = protocol::DecodeMessage<far_lcm::step_reply_t>(inner.data(), inner.size(),
                                                                 protocol::kMaxStepReplyBytes);
      auto full = protocol::ReceiveStepReply(inner, *replies_);
      if (!full) return std::nullopt;
      decoded.from_shm = stub.ok() && stub->reply_in_shm;
      decoded.step = std::move(*full);
      return decoded;
    }
    case MessageType::kError: {
      auto error = protocol::DecodeMessage<far_lcm::error_t>(inner.data(), inner.size(),
                                                             protocol::kMaxControlMessageBytes);
      if (!error) return std::nullopt;
      decoded.error = std::move(*error);
      return decoded;
    }
    case MessageType::kStepStatus: {
      auto status = protocol::DecodeMessage<far_lcm::step_status_t>(
          inner.data(), inner.size(), protocol::kMaxControlMessageBytes);
      if (!status) return std::nullopt;
      decoded.status = std::move(*status);
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
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return std::nullopt;
    auto got =
        listener_->WaitFor([&](const Received& r) { return r.channel == reply_channel_; }, left);
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
      [&](const ReplyMessage& m) { return m.step && m.step->step_id == step_id; }, timeout);
  if (!reply) return std::nullopt;
  return reply->step;
}

std::optional<ReplyMessage> RawSession::WaitError(int64_t request_id,
                                                  std::chrono::milliseconds timeout) {
  return WaitReply(
      [&](const ReplyMessage& m) { return m.error && m.error->request_id == request_id; }, timeout);
}

}  // namespace far::integration
