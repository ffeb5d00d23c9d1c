#include "far/client/client.h"

#include <atomic>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "far_lcm/close_session_t.hpp"
#include "far_lcm/error_t.hpp"
#include "far_lcm/heartbeat_t.hpp"
#include "far_lcm/open_session_reply_t.hpp"
#include "far_lcm/open_session_t.hpp"
#include "far_lcm/status_reply_t.hpp"
#include "far_lcm/status_request_t.hpp"
#include "far_lcm/step_reply_t.hpp"

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/message.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"
#include "far/protocol/version.h"

namespace far::client {
namespace {

// The public header cannot include protocol headers (they are not installed): its default URL
// must stay the protocol's.
static_assert(kDefaultLcmUrl == protocol::kDefaultLcmUrl);

using protocol::MessageType;
namespace wire = far_lcm;

std::string RandomHex(size_t bytes) {
  std::vector<uint8_t> random(bytes);
  protocol::RandomBytes(random.data(), random.size());
  static const char* kDigits = "0123456789abcdef";
  std::string hex;
  for (uint8_t b : random) {
    hex += kDigits[b >> 4];
    hex += kDigits[b & 15];
  }
  return hex;
}

int64_t RandomId() {
  int64_t id = 0;
  protocol::RandomBytes(reinterpret_cast<uint8_t*>(&id), sizeof(id));
  return id & 0x3fffffffffffffff;
}

Error NoDaemon(const std::string& url, std::chrono::milliseconds timeout) {
  return MakeError(ErrorCode::kUnavailable, "no far-daemon answered on " + url + " within " +
                                                std::to_string(timeout.count()) +
                                                " ms (is far-daemon running on this LCM URL?)");
}

// Runs an LCM bus's handlers on a background thread until stopped.
class BusThread {
 public:
  explicit BusThread(protocol::LcmBus* bus)
      : thread_([this, bus] {
          while (!stop_) bus->Handle(std::chrono::milliseconds(50));
        }) {}
  ~BusThread() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

struct Client::Impl {
  ClientOptions options;
  std::unique_ptr<protocol::LcmBus> bus;
  // Set once, last, when the session is open (release); the receive thread reads it (acquire)
  // before it touches the session's channel name, key and reply ring.
  std::atomic<int64_t> session_id{0};
  std::string request_channel, reply_channel;
  std::unique_ptr<protocol::ShmSegment> segment;
  std::unique_ptr<protocol::UpdateWriter> updates;
  std::unique_ptr<protocol::RingReader> replies;  // receive thread only
  protocol::SessionKey key{};

  std::mutex send_mutex;  // request ids are assigned and published in one order
  int64_t next_request_id = 1;
  int64_t next_step_id = 0;

  std::mutex mutex;  // pending steps, open reply, closed state
  std::condition_variable changed;
  std::optional<wire::open_session_reply_t> open_reply;
  int64_t open_request_id = 0;
  std::string open_channel;
  struct Pending {
    int64_t request_id = 0;
    std::promise<Result<StepResult>> promise;
  };
  std::map<int64_t, Pending> pending;  // by step id
  std::optional<Error> closed;         // set when the daemon ended the session

  std::unique_ptr<BusThread> receiver;
  std::thread heartbeat_thread;
  std::atomic<bool> stopping{false};

  void Fail(int64_t step_id, const Error& error) {
    std::lock_guard lock(mutex);
    auto it = pending.find(step_id);
    if (it == pending.end()) return;
    it->second.promise.set_value(error);
    pending.erase(it);
  }

  void FailAll(const Error& error) {
    std::lock_guard lock(mutex);
    for (auto& [id, p] : pending) p.promise.set_value(error);
    pending.clear();
    closed = error;
  }

  void OnOpenReply(std::span<const uint8_t> bytes) {
    auto reply = protocol::DecodeMessage<wire::open_session_reply_t>(
        bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
    if (!reply) return;
    std::lock_guard lock(mutex);
    if (reply->request_id != open_request_id) return;
    open_reply = std::move(*reply);
    changed.notify_all();
  }

  // Messages of our session: step replies, errors, heartbeat echoes. Anything that does not
  // carry our session key's tag is ignored (anyone on the host can publish on LCM).
  void OnSessionReply(std::span<const uint8_t> bytes) {
    auto type = protocol::IdentifyMessage(bytes.data(), bytes.size());
    if (!type) return;
    if (*type == MessageType::kStepReply) {
      auto stub = protocol::DecodeMessage<wire::step_reply_t>(bytes.data(), bytes.size(),
                                                              protocol::kMaxStepReplyBytes);
      if (!stub || !protocol::VerifyEncoded(bytes, key)) return;
      auto full = protocol::ReceiveStepReply(bytes.data(), bytes.size(), key, *replies);
      if (!full) return Fail(stub->step_id, full.error());
      auto result = protocol::ParseStepReply(*full);
      std::lock_guard lock(mutex);
      auto it = pending.find(full->step_id);
      if (it == pending.end()) return;  // a step we gave up on (timeout)
      if (result) {
        it->second.promise.set_value(std::move(*result));
      } else {
        it->second.promise.set_value(result.error());
      }
      pending.erase(it);
      return;
    }
    if (*type == MessageType::kError) {
      auto error = protocol::DecodeMessage<wire::error_t>(bytes.data(), bytes.size(),
                                                          protocol::kMaxControlMessageBytes);
      if (!error || !protocol::VerifyEncoded(bytes, key)) return;
      Error e = MakeError(protocol::FromWireStatus(error->status), "far-daemon: " + error->message);
      if (error->session_closed) return FailAll(e);
      std::lock_guard lock(mutex);
      for (auto it = pending.begin(); it != pending.end(); ++it) {
        if (it->second.request_id == error->request_id) {
          it->second.promise.set_value(e);
          pending.erase(it);
          break;
        }
      }
    }
  }

  Result<void> Send(auto&& message) {
    std::lock_guard lock(send_mutex);
    message.protocol_version = protocol::kProtocolVersion;
    message.session_id = session_id.load();
    message.request_id = next_request_id++;
    auto bytes = protocol::EncodeSigned(message, key);
    if (!bytes) return bytes.error();
    return bus->Publish(request_channel, *bytes);
  }

  Result<void> CheckOpen() {
    std::lock_guard lock(mutex);
    if (closed) return *closed;
    return {};
  }
};

Client::Client(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Client::~Client() { (void)Close(); }

Result<std::unique_ptr<Client>> Client::Connect(const ClientOptions& options) {
  auto impl = std::make_unique<Impl>();
  Impl& c = *impl;
  c.options = options;
  auto bus = protocol::LcmBus::Create(options.lcm_url);
  if (!bus) return bus.error();
  c.bus = std::move(*bus);
  // Subscribe before the receive thread starts: our open reply channel, and every session's
  // reply channel (our id is not known yet; the handler keeps only ours).
  c.open_channel = std::string(protocol::kOpenReplyPrefix) + RandomHex(12);
  Impl* raw = impl.get();
  c.bus->Subscribe(c.open_channel,
                   [raw](std::string_view, std::span<const uint8_t> b) { raw->OnOpenReply(b); });
  c.bus->Subscribe(
      "FAR_S[0-9]+_REPLY", [raw](std::string_view channel, std::span<const uint8_t> b) {
        if (raw->session_id.load(std::memory_order_acquire) != 0 && channel == raw->reply_channel)
          raw->OnSessionReply(b);
      });
  c.receiver = std::make_unique<BusThread>(c.bus.get());

  // Ask for a session and wait for the answer.
  wire::open_session_t open{};
  open.protocol_version = protocol::kProtocolVersion;
  c.open_request_id = RandomId();
  open.request_id = c.open_request_id;
  open.client_name = options.client_name;
  open.reply_channel = c.open_channel;
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes) return bytes.error();
  if (auto sent = c.bus->Publish(std::string(protocol::kOpenChannel), *bytes); !sent)
    return sent.error();
  wire::open_session_reply_t reply;
  {
    std::unique_lock lock(c.mutex);
    if (!c.changed.wait_for(lock, options.timeout, [&] { return c.open_reply.has_value(); })) {
      return NoDaemon(options.lcm_url, options.timeout);
    }
    reply = *c.open_reply;
  }
  if (reply.status != protocol::kWireOk) {
    return MakeError(protocol::FromWireStatus(reply.status),
                     "far-daemon refused the session: " + reply.message);
  }
  // Map the session's segment (checks owner, mode and header) and take its key.
  auto segment =
      protocol::ShmSegment::Open(reply.shm_name, static_cast<uint64_t>(reply.session_id));
  if (!segment) return segment.error();
  c.segment = std::move(*segment);
  c.key = c.segment->session_key();
  c.updates = std::make_unique<protocol::UpdateWriter>(c.segment->update_ring());
  c.replies = std::make_unique<protocol::RingReader>(c.segment->reply_ring(),
                                                     c.segment->layout().reply_ring_capacity);
  c.request_channel = reply.request_channel;
  c.reply_channel = reply.session_reply_channel;
  c.session_id.store(reply.session_id, std::memory_order_release);  // last: see its comment
  if (options.heartbeat) {
    const auto period =
        std::chrono::milliseconds(std::max<int64_t>(50, reply.heartbeat_timeout_ms / 4));
    c.heartbeat_thread = std::thread([raw, period] {
      auto next = std::chrono::steady_clock::now();
      while (!raw->stopping) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        if (std::chrono::steady_clock::now() < next) continue;
        next += period;
        (void)raw->Send(wire::heartbeat_t{});
      }
    });
  }
  return std::unique_ptr<Client>(new Client(std::move(impl)));
}

namespace {
template <typename T>
Result<void> Written(const Result<T>& written, const char* what) {
  if (written) return {};
  Error error = written.error();
  if (error.code == ErrorCode::kTimeout) {
    error.message = std::string(what) + ": the update ring stayed full (" + error.message +
                    "); call Step so the daemon drains it, or open the session with a bigger ring";
  }
  return error;
}

// The pose as it is sent: checked with the model's rule and normalized, so a quaternion written
// with a few decimals is sent as the unit quaternion it stands for, and a bad one is refused
// here, naming the call, instead of failing the next step.
Result<Pose> UnitPose(const Pose& X_WO, const char* what, uint32_t id) {
  Result<Pose> unit = CheckAndNormalizePose(X_WO);
  if (!unit) {
    return MakeError(unit.error().code, std::string(what) + ": object " + std::to_string(id) +
                                            ": X_WO." + unit.error().message);
  }
  return unit;
}
}  // namespace

Result<void> Client::AddObject(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO) {
  if (auto ok = impl_->CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "add_object", id);
  if (!unit) return unit.error();
  return Written(impl_->updates->AddObject(id, mesh, motion, *unit, impl_->options.timeout),
                 "add_object");
}
Result<void> Client::RemoveObject(uint32_t id) {
  if (auto ok = impl_->CheckOpen(); !ok) return ok;
  return Written(impl_->updates->RemoveObject(id, impl_->options.timeout), "remove_object");
}
Result<void> Client::SetPose(uint32_t id, const Pose& X_WO) {
  if (auto ok = impl_->CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "set_pose", id);
  if (!unit) return unit.error();
  return Written(impl_->updates->SetPose(id, *unit, impl_->options.timeout), "set_pose");
}
Result<void> Client::SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV) {
  if (auto ok = impl_->CheckOpen(); !ok) return ok;
  return Written(impl_->updates->SetVertices(id, p_MV, impl_->options.timeout), "set_vertices");
}

Result<void> Client::LoadScene(const Scene& scene) {
  for (const SceneObject& object : scene.objects) {
    if (auto ok = AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok) return ok;
  }
  return {};
}

Result<void> Client::ApplyFrame(const FrameUpdate& frame) {
  for (uint32_t id : frame.removals) {
    if (auto ok = RemoveObject(id); !ok) return ok;
  }
  for (const SceneObject& object : frame.additions) {
    if (auto ok = AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok) return ok;
  }
  for (const auto& [id, pose] : frame.poses) {
    if (auto ok = SetPose(id, pose); !ok) return ok;
  }
  for (const auto& [id, mesh] : frame.vertices) {
    if (auto ok = SetVertices(id, mesh.p_MV); !ok) return ok;
  }
  return {};
}

std::future<Result<StepResult>> Client::StepAsync(const StepRequest& request) {
  Impl& c = *impl_;
  std::promise<Result<StepResult>> promise;
  auto future = promise.get_future();
  if (auto ok = c.CheckOpen(); !ok) {
    promise.set_value(ok.error());
    return future;
  }
  std::lock_guard send_lock(c.send_mutex);
  const int64_t step_id = c.next_step_id++;
  const int64_t request_id = c.next_request_id++;
  {
    std::lock_guard lock(c.mutex);
    c.pending[step_id] = Impl::Pending{request_id, std::move(promise)};
  }
  auto message = protocol::MakeStepRequest(c.session_id.load(), request_id, step_id,
                                           c.updates->last_sequence(), request);
  auto bytes = protocol::EncodeSigned(message, c.key);
  Result<void> sent =
      bytes ? c.bus->Publish(c.request_channel, *bytes) : Result<void>(bytes.error());
  if (!sent) c.Fail(step_id, sent.error());
  return future;
}

Result<StepResult> Client::Step(const StepRequest& request) {
  const int64_t step_id = [&] {
    std::lock_guard lock(impl_->send_mutex);
    return impl_->next_step_id;
  }();
  auto future = StepAsync(request);
  if (future.wait_for(impl_->options.timeout) != std::future_status::ready) {
    impl_->Fail(step_id, MakeError(ErrorCode::kTimeout, "timeout"));
    return MakeError(ErrorCode::kTimeout, "no reply to step " + std::to_string(step_id) +
                                              " within " +
                                              std::to_string(impl_->options.timeout.count()) +
                                              " ms (far-daemon stopped or restarted?)");
  }
  return future.get();
}

Result<void> Client::Heartbeat() {
  if (auto ok = impl_->CheckOpen(); !ok) return ok;
  return impl_->Send(wire::heartbeat_t{});
}

Result<void> Client::Close() {
  Impl& c = *impl_;
  if (c.stopping.exchange(true)) return {};
  if (c.heartbeat_thread.joinable()) c.heartbeat_thread.join();
  Result<void> sent;
  if (c.session_id != 0 && c.CheckOpen()) sent = c.Send(wire::close_session_t{});
  c.receiver.reset();
  c.FailAll(MakeError(ErrorCode::kUnavailable, "the session is closed"));
  return sent;
}

int64_t Client::session_id() const { return impl_->session_id.load(); }
const std::string& Client::shm_name() const { return impl_->segment->name(); }

Result<DaemonStatus> Client::Status(const std::string& lcm_url, std::chrono::milliseconds timeout) {
  auto bus = protocol::LcmBus::Create(lcm_url);
  if (!bus) return bus.error();
  std::mutex mutex;
  std::condition_variable changed;
  std::optional<wire::status_reply_t> reply;
  const int64_t request_id = RandomId();
  (*bus)->Subscribe(std::string(protocol::kStatusReplyChannel),
                    [&](std::string_view, std::span<const uint8_t> b) {
                      auto message = protocol::DecodeMessage<wire::status_reply_t>(
                          b.data(), b.size(), protocol::kMaxStatusReplyBytes);
                      if (!message || message->request_id != request_id) return;
                      std::lock_guard lock(mutex);
                      reply = std::move(*message);
                      changed.notify_all();
                    });
  {
    BusThread receiver(bus->get());
    wire::status_request_t request{};
    request.protocol_version = protocol::kProtocolVersion;
    request.request_id = request_id;
    auto bytes = protocol::EncodeMessage(request);
    if (!bytes) return bytes.error();
    if (auto sent = (*bus)->Publish(std::string(protocol::kStatusChannel), *bytes); !sent)
      return sent.error();
    std::unique_lock lock(mutex);
    if (!changed.wait_for(lock, timeout, [&] { return reply.has_value(); }))
      return NoDaemon(lcm_url, timeout);
  }
  DaemonStatus status;
  status.daemon_version = reply->daemon_version;
  status.gl_renderer = reply->gl_renderer;
  status.uptime_ms = reply->uptime_ms;
  status.steps_total = reply->steps_total;
  status.errors_total = reply->errors_total;
  status.rejected_messages_total = reply->rejected_messages_total;
  status.max_sessions = reply->max_sessions;
  status.latency_p50_ms = reply->latency_p50_ms;
  status.latency_p90_ms = reply->latency_p90_ms;
  status.latency_p99_ms = reply->latency_p99_ms;
  status.latency_max_ms = reply->latency_max_ms;
  status.latency_samples = reply->latency_samples;
  for (int i = 0; i < reply->num_sessions; ++i) {
    status.sessions.push_back({reply->session_id[i], reply->session_client_name[i],
                               reply->session_steps[i], reply->session_objects[i],
                               reply->session_latency_p50_ms[i], reply->session_latency_p99_ms[i]});
  }
  for (int i = 0; i < reply->num_error_kinds; ++i) {
    status.errors_by_kind.emplace_back(reply->error_kind[i], reply->error_count[i]);
  }
  return status;
}

}  // namespace far::client
