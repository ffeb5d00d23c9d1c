#include "far/client/client.h"

#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "daemon_connection.h"
#include "session_recorder.h"

#include "far/client/internal/client_access.h"
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

// The public header cannot include protocol headers (they are not installed): its default
// name must stay the protocol's.
static_assert(kDefaultDaemonName == protocol::kDefaultDaemonName);

using protocol::MessageType;
namespace wire = far_lcm;

// A full update ring is waited on this long at most: the daemon drains it only at a step, so
// a longer wait would only delay the error.
constexpr std::chrono::seconds kRingWait{5};

// A distance left at the default output (contacts) asks for distance pairs, as far-client's
// --distance does: otherwise the caller gets an empty list and no error.
StepRequest RequestToSend(StepRequest request) {
  if (request.distance && request.output == Output::kContacts) {
    request.output = Output::kDistancePairs;
  }
  return request;
}

}  // namespace

struct Client::Impl {
  ClientOptions options;
  protocol::LocalConnection connection{-1};  // the session lives as long as this does
  std::unique_ptr<protocol::LcmBus> bus;
  int64_t session_id = 0;
  std::string request_channel, reply_channel;
  std::unique_ptr<protocol::ShmSegment> segment;
  std::unique_ptr<protocol::UpdateWriter> updates;
  std::unique_ptr<protocol::RingReader> replies;  // receive thread only
  protocol::SessionKey key{};
  int64_t last_sealed_id = 0;  // receive thread only: the daemon's sequence, strictly growing

  std::mutex send_mutex;  // request ids are assigned and published in one order
  int64_t next_request_id = 1;
  int64_t next_step_id = 0;

  std::mutex mutex;  // pending steps and the closed state
  struct Pending {
    int64_t request_id = 0;
    std::promise<Result<StepResult>> promise;
    ProgressCallback on_progress;
  };
  std::map<int64_t, Pending> pending;  // by step id
  std::optional<Error> closed;         // set when the session ended

  std::thread receiver;
  std::atomic<bool> stopping{false};
  std::unique_ptr<internal::SessionRecorder> recorder;  // null: not recording

  int64_t NextStepId() {
    std::lock_guard lock(send_mutex);
    return next_step_id;
  }

  // Records how a pending step ended without a reply of its own (call with `mutex` held).
  void RecordError(int64_t step_id, const Pending& p, const Error& error) {
    if (recorder) recorder->ErrorReply({session_id, p.request_id, step_id, 0}, error);
  }

  void Fail(int64_t step_id, const Error& error) {
    std::lock_guard lock(mutex);
    auto it = pending.find(step_id);
    if (it == pending.end()) return;
    RecordError(step_id, it->second, error);
    it->second.promise.set_value(error);
    pending.erase(it);
  }

  void FailAll(const Error& error) {
    std::lock_guard lock(mutex);
    for (auto& [id, p] : pending) {
      RecordError(id, p, error);
      p.promise.set_value(error);
    }
    pending.clear();
    if (!closed) closed = error;
  }

  void OnStepReply(std::span<const uint8_t> inner) {
    auto full = protocol::ReceiveStepReply(inner, *replies);
    if (!full) return;  // (a stub whose record is gone: the step times out with a clear error)
    auto result = protocol::ParseStepReply(*full);
    std::lock_guard lock(mutex);
    auto it = pending.find(full->step_id);
    if (it == pending.end()) return;  // a step we gave up on (timeout)
    if (recorder) {
      // A reply that does not parse is recorded as the error the caller got.
      if (result || full->status != protocol::kWireOk) {
        recorder->Reply(*full);
      } else {
        RecordError(full->step_id, it->second, result.error());
      }
    }
    if (result) {
      it->second.promise.set_value(std::move(*result));
    } else {
      it->second.promise.set_value(result.error());
    }
    pending.erase(it);
  }

  void OnStepStatus(std::span<const uint8_t> inner) {
    auto status = protocol::DecodeMessage<wire::step_status_t>(inner.data(), inner.size(),
                                                               protocol::kMaxControlMessageBytes);
    if (!status) return;
    ProgressCallback callback;
    {
      std::lock_guard lock(mutex);
      auto it = pending.find(status->step_id);
      if (it == pending.end() || !it->second.on_progress) return;
      callback = it->second.on_progress;
    }
    callback(
        {status->state, status->queue_position, ParseStage(status->stage), status->elapsed_ms});
  }

  void OnError(std::span<const uint8_t> inner) {
    auto error = protocol::DecodeMessage<wire::error_t>(inner.data(), inner.size(),
                                                        protocol::kMaxControlMessageBytes);
    if (!error) return;
    Error e = MakeError(protocol::FromWireStatus(error->status), "far-daemon: " + error->message);
    if (error->session_closed) return FailAll(e);
    std::lock_guard lock(mutex);
    for (auto it = pending.begin(); it != pending.end(); ++it) {
      if (it->second.request_id == error->request_id) {
        RecordError(it->first, it->second, e);
        it->second.promise.set_value(e);
        pending.erase(it);
        break;
      }
    }
  }

  // Every message of our reply channel is sealed with our key: anything else (a forgery, a
  // replay, another session's) does not open and is ignored.
  void OnReply(std::span<const uint8_t> bytes) {
    auto opened = protocol::OpenSealed(bytes.data(), bytes.size(), session_id, key,
                                       protocol::kMaxStepReplyBytes);
    if (!opened || opened->request_id <= last_sealed_id) return;
    last_sealed_id = opened->request_id;
    auto type = protocol::IdentifyMessage(opened->inner.data(), opened->inner.size());
    if (!type) return;
    if (*type == MessageType::kStepReply) return OnStepReply(opened->inner);
    if (*type == MessageType::kStepStatus) return OnStepStatus(opened->inner);
    if (*type == MessageType::kError) return OnError(opened->inner);
  }

  // The receive thread: LCM replies, and the daemon's end of the connection: when it closes
  // (the daemon stopped, restarted or ended the session) every waiting step fails at once.
  void Receive() {
    while (!stopping) {
      bus->Handle(std::chrono::milliseconds(50));
      if (connection.PeerClosed()) {
        FailAll(MakeError(ErrorCode::kUnavailable,
                          "far-daemon ended the session (it stopped, restarted or closed it)"));
        return;
      }
    }
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
  auto connection = internal::ConnectToDaemon(options);
  if (!connection) return connection.error();
  c.connection = std::move(*connection);
  auto opened = internal::OpenSession(c.connection, options);
  if (!opened) return opened.error();
  const wire::open_session_reply_t& reply = opened->reply;
  c.session_id = reply.session_id;
  c.segment = std::move(opened->segment);
  c.key = c.segment->session_key();
  c.updates = std::make_unique<protocol::UpdateWriter>(c.segment->update_ring());
  c.replies = std::make_unique<protocol::RingReader>(c.segment->reply_ring(),
                                                     c.segment->layout().reply_ring_capacity);
  c.request_channel = reply.request_channel;
  c.reply_channel = reply.session_reply_channel;
  auto recorder = internal::StartRecording(options, c.session_id);
  if (!recorder) return recorder.error();
  c.recorder = std::move(*recorder);
  // The session's channels are where the daemon says, unless the caller insists.
  const std::string& lcm_url = options.lcm_url.empty() ? reply.lcm_url : options.lcm_url;
  if (protocol::IsInProcessUrl(lcm_url)) {
    // Every step would wait out its timeout: no message leaves a memq:// LCM instance.
    return MakeError(ErrorCode::kUnavailable,
                     "the session's LCM URL is " + lcm_url +
                         ", which carries messages only within one LCM instance: no client can "
                         "reach the daemon's channels. Start far-daemon with a udpm:// URL "
                         "(its default) or give the client one with --lcm-url / "
                         "ClientOptions::lcm_url");
  }
  auto bus = protocol::LcmBus::Create(lcm_url);
  if (!bus) return bus.error();
  c.bus = std::move(*bus);
  Impl* raw = impl.get();
  c.bus->Subscribe(c.reply_channel,
                   [raw](std::string_view, std::span<const uint8_t> b) { raw->OnReply(b); });
  c.receiver = std::thread([raw] { raw->Receive(); });
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
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "add_object", id);
  if (!unit) return unit.error();
  auto written = c.updates->AddObject(id, mesh, motion, *unit, kRingWait);
  if (written && c.recorder) {
    c.recorder->AddObject(written->sequence, c.NextStepId(), id, mesh, motion, *unit);
  }
  return Written(written, "add_object");
}
Result<void> Client::RemoveObject(uint32_t id) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  auto written = c.updates->RemoveObject(id, kRingWait);
  if (written && c.recorder) c.recorder->RemoveObject(written->sequence, c.NextStepId(), id);
  return Written(written, "remove_object");
}
Result<void> Client::SetPose(uint32_t id, const Pose& X_WO) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "set_pose", id);
  if (!unit) return unit.error();
  auto written = c.updates->SetPose(id, *unit, kRingWait);
  if (written && c.recorder) c.recorder->SetPose(written->sequence, c.NextStepId(), id, *unit);
  return Written(written, "set_pose");
}
Result<void> Client::SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  auto written = c.updates->SetVertices(id, p_MV, kRingWait);
  if (written && c.recorder) {
    c.recorder->SetVertices(written->sequence, c.NextStepId(), id, p_MV);
  }
  return Written(written, "set_vertices");
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

std::future<Result<StepResult>> Client::StepAsync(const StepRequest& request,
                                                  ProgressCallback on_progress) {
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
    c.pending[step_id] = Impl::Pending{request_id, std::move(promise), std::move(on_progress)};
  }
  const auto timeout_ms = static_cast<int32_t>(
      std::min<int64_t>(c.options.timeout.count(), std::numeric_limits<int32_t>::max()));
  auto message =
      protocol::MakeStepRequest(c.session_id, request_id, step_id, c.updates->last_sequence(),
                                RequestToSend(request), timeout_ms);
  // Recorded before it is sent, so that the request comes before its reply in the file.
  if (c.recorder) c.recorder->Request(message);
  auto bytes = protocol::EncodeSigned(message, c.key);
  Result<void> sent =
      bytes ? c.bus->Publish(c.request_channel, *bytes) : Result<void>(bytes.error());
  if (!sent) c.Fail(step_id, sent.error());
  return future;
}

Result<StepResult> Client::Step(const StepRequest& request, const ProgressCallback& on_progress) {
  const int64_t step_id = [&] {
    std::lock_guard lock(impl_->send_mutex);
    return impl_->next_step_id;
  }();
  auto future = StepAsync(request, on_progress);
  if (future.wait_for(impl_->options.timeout) != std::future_status::ready) {
    impl_->Fail(step_id, MakeError(ErrorCode::kTimeout, "timeout"));
    return MakeError(ErrorCode::kTimeout,
                     "step " + std::to_string(step_id) + " was not answered within " +
                         std::to_string(impl_->options.timeout.count()) +
                         " ms, the client's limit (the daemon is still running; raise the "
                         "timeout for bigger scenes)");
  }
  return future.get();
}

Result<void> Client::Close() {
  Impl& c = *impl_;
  if (c.stopping.exchange(true)) return {};
  if (c.receiver.joinable()) c.receiver.join();
  // Closing the connection ends the session: the daemon frees it at once.
  c.connection = protocol::LocalConnection(-1);
  c.FailAll(MakeError(ErrorCode::kUnavailable, "the session is closed"));
  return {};
}

int64_t Client::session_id() const { return impl_->session_id; }

std::string Client::recording_path() const {
  return impl_->recorder ? impl_->recorder->path() : std::string();
}

namespace internal {

protocol::UpdateWriter& ClientAccess::Updates(Client& client) { return *client.impl_->updates; }

Result<std::unique_ptr<SessionRecorder>> StartRecording(const ClientOptions& options,
                                                        int64_t session_id) {
  std::string path;
  if (options.record_path) {
    path = *options.record_path;
  } else if (const char* env = std::getenv("FAR_RECORD"); env != nullptr) {
    path = env;
  }
  if (path.empty()) return std::unique_ptr<SessionRecorder>();
  SessionRecorder::Info info{options.client_name, "", "", session_id};
  // The daemon's name and renderer tell replay whether GPU answers may differ; a daemon that
  // does not answer leaves them unknown.
  if (auto status = Client::Status(options); status) {
    info.daemon_name = status->daemon_name;
    info.gl_renderer = status->gl_renderer;
  }
  return SessionRecorder::Create(path, info);
}

}  // namespace internal

Result<DaemonStatus> Client::Status(const ClientOptions& options) {
  auto connection = internal::ConnectToDaemon(options);
  if (!connection) return connection.error();
  return internal::RequestStatus(*connection, options);
}

}  // namespace far::client
