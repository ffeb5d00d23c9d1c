#include "daemon.h"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <variant>

#include "fair_scheduler.h"
#include "far_lcm/close_session_t.hpp"
#include "far_lcm/error_t.hpp"
#include "far_lcm/heartbeat_t.hpp"
#include "far_lcm/open_session_reply_t.hpp"
#include "far_lcm/open_session_t.hpp"
#include "far_lcm/status_reply_t.hpp"
#include "far_lcm/status_request_t.hpp"
#include "far_lcm/step_reply_t.hpp"
#include "far_lcm/step_request_t.hpp"
#include "latency_stats.h"
#include <spdlog/spdlog.h>

#include "far/gpu/gl_context.h"
#include "far/pipeline/pipeline.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/message.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"
#include "far/protocol/version.h"

namespace far::server {
namespace {

using Clock = std::chrono::steady_clock;
using protocol::MessageType;
namespace wire = far_lcm;

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now().time_since_epoch())
      .count();
}

// What the daemon knows of one object of a session, to check updates before applying them.
struct ObjectInfo {
  Motion motion = Motion::kStatic;
  uint32_t vertices = 0;
  uint32_t triangles = 0;
};

// One client's session. Fields are owned by the thread named in their comment.
struct Session {
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
  std::unique_ptr<Pipeline> pipeline;
  std::map<uint32_t, ObjectInfo> objects;
  int64_t triangles = 0;
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

struct StepJob {
  std::shared_ptr<Session> session;
  protocol::StepCommand command;
  Clock::time_point received;
};

}  // namespace

struct Daemon::Impl {
  DaemonConfig config;
  std::unique_ptr<protocol::LcmBus> bus;
  std::atomic<bool> stop{false};
  Clock::time_point started = Clock::now();

  std::mutex mutex;  // guards sessions, scheduler, to_destroy, next_session_id
  std::condition_variable work;
  std::map<int64_t, std::shared_ptr<Session>> sessions;
  FairScheduler<StepJob> scheduler;
  std::vector<std::shared_ptr<Session>> to_destroy;  // closed: the GL thread frees them
  int64_t next_session_id = 1;

  std::mutex stats_mutex;
  LatencyWindow latency{8192};
  std::map<std::string, int64_t> errors_by_kind;
  std::atomic<int64_t> steps_total{0}, errors_total{0}, rejected_total{0};
  std::string renderer;

  explicit Impl(const DaemonConfig& c)
      : config(c),
        scheduler(SchedulerLimits{
            static_cast<size_t>(c.max_queued_per_session), static_cast<size_t>(c.max_queued_total),
            c.max_requests_per_second, std::max(8.0, c.max_requests_per_second / 20)}) {}

  void CountError(const std::string& kind) {
    std::lock_guard lock(stats_mutex);
    errors_by_kind[kind]++;
    errors_total++;
  }

  // A message we drop without a session to answer in: counted and logged.
  void Reject(std::string_view channel, const Error& error) {
    rejected_total++;
    CountError("rejected_message");
    spdlog::warn("event=message_rejected channel={} reason=\"{}\"", channel, ToString(error));
  }

  void Publish(const std::string& channel, const std::vector<uint8_t>& bytes) {
    if (auto ok = bus->Publish(channel, bytes); !ok) {
      spdlog::error("event=publish_failed channel={} reason=\"{}\"", channel, ok.error().message);
    }
  }

  // An error_t on a session's reply channel. Signed with the session key when we have one, so
  // the session's client trusts it; unsigned (zero auth) for unknown or unauthenticated senders.
  void PublishError(int64_t session_id, const protocol::SessionKey* key, int64_t request_id,
                    const Error& error, bool session_closed) {
    CountError(far::ToString(error.code));
    auto message = protocol::MakeErrorMessage(session_id, request_id, error, session_closed);
    if (key != nullptr) {
      auto bytes = protocol::EncodeSigned(message, *key);
      if (bytes) Publish(protocol::SessionReplyChannel(session_id), *bytes);
    } else {
      auto bytes = protocol::EncodeMessage(message);
      if (bytes) Publish(protocol::SessionReplyChannel(session_id), *bytes);
    }
  }

  // A failed step's reply (the client waits for a step_reply_t with its step id).
  void PublishStepError(Session& session, const protocol::StepCommand& command,
                        const Error& error) {
    CountError(far::ToString(error.code));
    protocol::StepReplyIds ids{session.id, session.next_reply_id++, command.step_id,
                               session.applied_sequence.load()};
    auto bytes = protocol::EncodeSigned(protocol::MakeStepErrorReply(ids, error), session.key);
    if (bytes) Publish(session.reply_channel, *bytes);
    spdlog::info("event=step_error session={} step={} code={} reason=\"{}\"", session.id,
                 command.step_id, far::ToString(error.code), error.message);
  }

  // --- LCM thread --------------------------------------------------------------------------

  void OnOpen(std::string_view channel, std::span<const uint8_t> bytes) {
    auto message = protocol::DecodeMessage<wire::open_session_t>(bytes.data(), bytes.size(),
                                                                 protocol::kMaxControlMessageBytes);
    if (!message && message.error().code == ErrorCode::kVersionMismatch) {
      // A client of another protocol version: tell it so on its reply channel, if it named one.
      auto any = protocol::DecodeMessageAnyVersion<wire::open_session_t>(
          bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
      if (any && protocol::IsValidOpenReplyChannel(any->reply_channel)) {
        wire::open_session_reply_t reply{};
        reply.protocol_version = protocol::kProtocolVersion;
        reply.request_id = any->request_id;
        reply.status = protocol::ToWireStatus(ErrorCode::kVersionMismatch);
        reply.status_name = far::ToString(ErrorCode::kVersionMismatch);
        reply.message = message.error().message;
        CountError(reply.status_name);
        if (auto out = protocol::EncodeMessage(reply)) Publish(any->reply_channel, *out);
        return;
      }
    }
    if (!message) return Reject(channel, message.error());
    auto params = protocol::ValidateOpenSession(*message);
    wire::open_session_reply_t reply{};
    reply.protocol_version = protocol::kProtocolVersion;
    reply.request_id = message->request_id;
    auto fail = [&](const Error& error) {
      CountError(far::ToString(error.code));
      reply.status = protocol::ToWireStatus(error.code);
      reply.status_name = far::ToString(error.code);
      reply.message = error.message;
      spdlog::warn("event=open_refused client=\"{}\" reason=\"{}\"", message->client_name,
                   ToString(error));
    };
    if (!params) {
      // Answer only on a well-formed reply channel: never publish where a client did not ask.
      if (!protocol::IsValidOpenReplyChannel(message->reply_channel))
        return Reject(channel, params.error());
      fail(params.error());
      if (auto out = protocol::EncodeMessage(reply)) Publish(message->reply_channel, *out);
      return;
    }
    std::shared_ptr<Session> session;
    {
      std::lock_guard lock(mutex);
      if (stop) {
        fail(MakeError(ErrorCode::kUnavailable, "the daemon is shutting down"));
      } else if (static_cast<int>(sessions.size()) >= config.max_sessions) {
        fail(MakeError(
            ErrorCode::kLimitExceeded,
            "max_sessions: " + std::to_string(config.max_sessions) + " sessions are open"));
      } else {
        session = std::make_shared<Session>();
        session->id = next_session_id++;
      }
    }
    if (session) {
      protocol::SegmentOptions options;
      options.update_ring_bytes =
          params->update_ring_bytes ? params->update_ring_bytes : config.ring_bytes;
      options.reply_ring_bytes =
          params->reply_ring_bytes ? params->reply_ring_bytes : config.reply_bytes;
      // A client may ask for smaller rings than the daemon's, never larger ones.
      const bool too_large = options.update_ring_bytes > config.ring_bytes ||
                             options.reply_ring_bytes > config.reply_bytes;
      auto segment =
          too_large ? Result<std::unique_ptr<protocol::ShmSegment>>(MakeError(
                          ErrorCode::kLimitExceeded,
                          "update_ring_bytes/reply_ring_bytes: this daemon allows at most " +
                              std::to_string(config.ring_bytes) + "/" +
                              std::to_string(config.reply_bytes) + " bytes"))
                    : protocol::ShmSegment::Create(static_cast<uint64_t>(session->id), options);
      if (!segment) {
        fail(segment.error());
        session.reset();
      } else {
        session->segment = std::move(*segment);
        session->client_name = params->client_name;
        session->key = session->segment->session_key();
        session->request_channel = protocol::SessionRequestChannel(session->id);
        session->reply_channel = protocol::SessionReplyChannel(session->id);
        protocol::RingLimits limits;
        limits.max_vertices =
            static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session * 3, 1 << 30));
        limits.max_triangles =
            static_cast<uint32_t>(std::min<int64_t>(config.max_triangles_per_session, 1 << 30));
        session->updates =
            std::make_unique<protocol::UpdateReader>(session->segment->update_ring(), limits);
        session->replies = std::make_unique<protocol::RingWriter>(session->segment->reply_ring());
        session->last_heard_ms = NowMs();
        const auto& layout = session->segment->layout();
        reply.status = protocol::kWireOk;
        reply.status_name = "ok";
        reply.session_id = session->id;
        reply.shm_name = session->segment->name();
        reply.shm_bytes = static_cast<int64_t>(layout.segment_size);
        reply.ring_layout_version = static_cast<int32_t>(protocol::kLayoutVersion);
        reply.update_ring_bytes = static_cast<int64_t>(layout.update_ring_capacity);
        reply.reply_ring_bytes = static_cast<int64_t>(layout.reply_ring_capacity);
        reply.request_channel = session->request_channel;
        reply.session_reply_channel = session->reply_channel;
        reply.heartbeat_timeout_ms = config.heartbeat_timeout_ms;
        reply.max_objects =
            static_cast<int32_t>(std::min<int64_t>(config.max_objects_per_session, INT32_MAX));
        reply.max_vertices_per_object = static_cast<int32_t>(limits.max_vertices);
        reply.max_triangles_per_object = static_cast<int32_t>(limits.max_triangles);
        std::lock_guard lock(mutex);
        sessions[session->id] = session;
      }
    }
    if (auto out = protocol::EncodeMessage(reply)) Publish(params->reply_channel, *out);
    if (session) {
      spdlog::info("event=session_open session={} client=\"{}\" shm={}", session->id,
                   session->client_name, session->segment->name());
    }
  }

  std::shared_ptr<Session> FindSession(int64_t id) {
    std::lock_guard lock(mutex);
    auto it = sessions.find(id);
    return it == sessions.end() ? nullptr : it->second;
  }

  // Removes a session: its queued steps are answered with an error, its GL resources and
  // segment are freed on the GL thread.
  void CloseSession(int64_t id, const std::string& reason, bool tell_client) {
    std::shared_ptr<Session> session;
    std::deque<StepJob> pending;
    {
      std::lock_guard lock(mutex);
      auto it = sessions.find(id);
      if (it == sessions.end()) return;
      session = it->second;
      sessions.erase(it);
      pending = scheduler.RemoveSession(id);
      to_destroy.push_back(session);
    }
    work.notify_one();
    for (const StepJob& job : pending) {
      PublishStepError(*session, job.command,
                       MakeError(ErrorCode::kUnavailable, "session closed: " + reason));
    }
    if (tell_client) {
      PublishError(id, &session->key, -1,
                   MakeError(ErrorCode::kTimeout, "session closed: " + reason), true);
    }
    spdlog::info("event=session_close session={} reason=\"{}\"", id, reason);
  }

  // Decodes, authenticates and replay-checks a session message. On failure answers (unsigned)
  // on the session's reply channel and returns nullopt.
  template <typename T>
  std::optional<std::pair<T, std::shared_ptr<Session>>> OpenSessionMessage(
      std::string_view channel, int64_t channel_session, std::span<const uint8_t> bytes) {
    auto message =
        protocol::DecodeMessage<T>(bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
    if (!message) {
      Reject(channel, message.error());
      PublishError(channel_session, nullptr, -1, message.error(), false);
      return std::nullopt;
    }
    if (message->session_id != channel_session) {
      Error error = MakeError(ErrorCode::kInvalidArgument,
                              "session_id: " + std::to_string(message->session_id) +
                                  " does not match channel " + std::string(channel));
      Reject(channel, error);
      PublishError(channel_session, nullptr, message->request_id, error, false);
      return std::nullopt;
    }
    auto session = FindSession(channel_session);
    if (!session) {
      Error error = MakeError(ErrorCode::kNotFound,
                              "session_id: no open session " + std::to_string(channel_session));
      Reject(channel, error);
      PublishError(channel_session, nullptr, message->request_id, error, true);
      return std::nullopt;
    }
    if (auto ok = protocol::VerifyEncoded(bytes, session->key); !ok) {
      Reject(channel, ok.error());
      PublishError(channel_session, nullptr, message->request_id, ok.error(), false);
      return std::nullopt;
    }
    if (message->request_id <= session->last_request_id) {
      Error error = MakeError(
          ErrorCode::kInvalidArgument,
          "request_id: " + std::to_string(message->request_id) + " is not above the last one (" +
              std::to_string(session->last_request_id) + "): replayed or reordered");
      Reject(channel, error);
      PublishError(channel_session, &session->key, message->request_id, error, false);
      return std::nullopt;
    }
    session->last_request_id = message->request_id;
    session->last_heard_ms = NowMs();
    return std::make_pair(std::move(*message), std::move(session));
  }

  void OnSessionRequest(std::string_view channel, std::span<const uint8_t> bytes) {
    auto channel_session = protocol::ParseSessionRequestChannel(channel);
    if (!channel_session)
      return Reject(channel, MakeError(ErrorCode::kInvalidArgument, "unknown channel"));
    auto type = protocol::IdentifyMessage(bytes.data(), bytes.size());
    if (!type) {
      Reject(channel, type.error());
      PublishError(*channel_session, nullptr, -1, type.error(), false);
      return;
    }
    switch (*type) {
      case MessageType::kStepRequest: {
        auto opened = OpenSessionMessage<wire::step_request_t>(channel, *channel_session, bytes);
        if (!opened) return;
        auto& [message, session] = *opened;
        auto command = protocol::ValidateStepRequest(message);
        if (command && command->request.resolution > config.max_resolution) {
          command = MakeError(ErrorCode::kLimitExceeded,
                              "resolution: " + std::to_string(command->request.resolution) +
                                  " is over this daemon's max_resolution " +
                                  std::to_string(config.max_resolution));
        }
        if (!command) {
          protocol::StepCommand failed;
          failed.step_id = message.step_id;
          PublishStepError(*session, failed, command.error());
          return;
        }
        Result<void> queued = MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
        if (!stop) {
          std::lock_guard lock(mutex);
          queued = scheduler.Push(session->id, StepJob{session, *command, Clock::now()});
        }
        if (!queued) return PublishStepError(*session, *command, queued.error());
        work.notify_one();
        return;
      }
      case MessageType::kHeartbeat: {
        auto opened = OpenSessionMessage<wire::heartbeat_t>(channel, *channel_session, bytes);
        if (!opened) return;
        auto& [message, session] = *opened;
        wire::heartbeat_t reply = message;
        reply.request_id = session->next_reply_id++;
        reply.last_applied_sequence = static_cast<int64_t>(session->applied_sequence.load());
        reply.last_step_id = session->last_step_id.load();
        if (auto out = protocol::EncodeSigned(reply, session->key))
          Publish(session->reply_channel, *out);
        return;
      }
      case MessageType::kCloseSession: {
        auto opened = OpenSessionMessage<wire::close_session_t>(channel, *channel_session, bytes);
        if (opened) CloseSession(opened->second->id, "closed by the client", false);
        return;
      }
      default: {
        Error error = MakeError(
            ErrorCode::kInvalidArgument,
            std::string(protocol::ToString(*type)) + " is not a client-to-daemon session message");
        Reject(channel, error);
        PublishError(*channel_session, nullptr, -1, error, false);
      }
    }
  }

  void OnStatus(std::string_view channel, std::span<const uint8_t> bytes) {
    auto message = protocol::DecodeMessage<wire::status_request_t>(
        bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
    if (!message) return Reject(channel, message.error());
    wire::status_reply_t reply{};
    reply.protocol_version = protocol::kProtocolVersion;
    reply.request_id = message->request_id;
    reply.daemon_version = "0.1.0";
    {
      std::lock_guard lock(stats_mutex);
      reply.gl_renderer = renderer.empty() ? "none" : renderer;
      reply.latency_p50_ms = latency.Quantile(0.5);
      reply.latency_p90_ms = latency.Quantile(0.9);
      reply.latency_p99_ms = latency.Quantile(0.99);
      reply.latency_max_ms = latency.Quantile(1.0);
      reply.latency_samples = static_cast<int64_t>(latency.count());
      for (const auto& [kind, count] : errors_by_kind) {
        reply.error_kind.push_back(kind);
        reply.error_count.push_back(count);
      }
      reply.num_error_kinds = static_cast<int32_t>(reply.error_kind.size());
    }
    reply.uptime_ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - started).count();
    reply.max_sessions = config.max_sessions;
    reply.steps_total = steps_total;
    reply.errors_total = errors_total;
    reply.rejected_messages_total = rejected_total;
    std::vector<std::shared_ptr<Session>> open;
    {
      std::lock_guard lock(mutex);
      for (const auto& [id, session] : sessions) open.push_back(session);
    }
    for (const auto& session : open) {
      reply.session_id.push_back(session->id);
      reply.session_client_name.push_back(session->client_name);
      reply.session_steps.push_back(session->steps);
      reply.session_objects.push_back(session->num_objects);
      std::lock_guard lock(session->latency_mutex);
      reply.session_latency_p50_ms.push_back(session->latency.Quantile(0.5));
      reply.session_latency_p99_ms.push_back(session->latency.Quantile(0.99));
    }
    reply.num_sessions = static_cast<int32_t>(open.size());
    if (auto out = protocol::EncodeMessage(reply))
      Publish(std::string(protocol::kStatusReplyChannel), *out);
  }

  // Closes sessions whose client stopped sending anything for heartbeat_timeout_ms.
  void ReapSilentSessions() {
    const int64_t now = NowMs();
    std::vector<int64_t> silent;
    {
      std::lock_guard lock(mutex);
      for (const auto& [id, session] : sessions) {
        if (now - session->last_heard_ms > config.heartbeat_timeout_ms) silent.push_back(id);
      }
    }
    for (int64_t id : silent) {
      CloseSession(id, "no heartbeat for " + std::to_string(config.heartbeat_timeout_ms) + " ms",
                   true);
    }
  }

  // --- GL thread ---------------------------------------------------------------------------

  // Checks a batch of updates against the session's scene and limits, then applies it. A bad
  // update changes nothing: the scene stays as the previous step left it.
  Result<void> ApplyUpdates(Session& session, std::vector<protocol::SequencedUpdate>& updates) {
    std::map<uint32_t, std::optional<ObjectInfo>> changed;
    int64_t triangles = session.triangles;
    int64_t objects = static_cast<int64_t>(session.objects.size());
    auto find = [&](uint32_t id) -> std::optional<ObjectInfo> {
      if (auto it = changed.find(id); it != changed.end()) return it->second;
      if (auto it = session.objects.find(id); it != session.objects.end()) return it->second;
      return std::nullopt;
    };
    for (const auto& [sequence, update] : updates) {
      const std::string where = "ring record " + std::to_string(sequence);
      auto error = std::visit(
          [&](const auto& u) -> std::optional<Error> {
            using T = std::decay_t<decltype(u)>;
            const std::string object = where + " object " + std::to_string(u.id);
            auto info = find(u.id);
            if constexpr (std::is_same_v<T, protocol::AddObject>) {
              if (info)
                return MakeError(ErrorCode::kInvalidArgument,
                                 object + ": add_object: id is already in use");
              triangles += u.mesh.num_triangles();
              objects += 1;
              if (triangles > config.max_triangles_per_session) {
                return MakeError(ErrorCode::kLimitExceeded,
                                 object + ": add_object: the session would have " +
                                     std::to_string(triangles) + " triangles (limit " +
                                     std::to_string(config.max_triangles_per_session) + ")");
              }
              if (objects > config.max_objects_per_session) {
                return MakeError(ErrorCode::kLimitExceeded,
                                 object + ": add_object: more than " +
                                     std::to_string(config.max_objects_per_session) + " objects");
              }
              changed[u.id] = ObjectInfo{u.motion, static_cast<uint32_t>(u.mesh.num_vertices()),
                                         static_cast<uint32_t>(u.mesh.num_triangles())};
            } else if (!info) {
              return MakeError(ErrorCode::kNotFound, object + ": no such object");
            } else if constexpr (std::is_same_v<T, protocol::RemoveObject>) {
              triangles -= info->triangles;
              objects -= 1;
              changed[u.id] = std::nullopt;
            } else if constexpr (std::is_same_v<T, protocol::SetPose>) {
              if (info->motion == Motion::kStatic) {
                return MakeError(ErrorCode::kInvalidArgument,
                                 object + ": set_pose: the object is static");
              }
            } else {
              if (info->motion != Motion::kDeformable) {
                return MakeError(ErrorCode::kInvalidArgument,
                                 object + ": set_vertices: the object is not deformable");
              }
              if (u.p_MV.size() != info->vertices) {
                return MakeError(ErrorCode::kInvalidArgument,
                                 object + ": set_vertices: " + std::to_string(u.p_MV.size()) +
                                     " vertices, the object has " + std::to_string(info->vertices));
              }
            }
            return std::nullopt;
          },
          update);
      if (error) return *error;
    }
    // Every update is valid for this scene: apply them in order.
    for (auto& [sequence, update] : updates) {
      Result<void> applied = std::visit(
          [&](auto& u) -> Result<void> {
            using T = std::decay_t<decltype(u)>;
            if constexpr (std::is_same_v<T, protocol::AddObject>) {
              return session.pipeline->AddObject(u.id, std::move(u.mesh), u.motion, u.X_WO);
            } else if constexpr (std::is_same_v<T, protocol::RemoveObject>) {
              return session.pipeline->RemoveObject(u.id);
            } else if constexpr (std::is_same_v<T, protocol::SetPose>) {
              return session.pipeline->SetPose(u.id, u.X_WO);
            } else {
              return session.pipeline->SetVertices(u.id, std::move(u.p_MV));
            }
          },
          update);
      if (!applied)
        return MakeError(ErrorCode::kInternal, "ring record " + std::to_string(sequence) + ": " +
                                                   applied.error().message);
    }
    for (const auto& [id, info] : changed) {
      if (info) {
        session.objects[id] = *info;
      } else {
        session.objects.erase(id);
      }
    }
    session.triangles = triangles;
    session.num_objects = static_cast<int>(session.objects.size());
    return {};
  }

  void RunStep(StepJob& job) {
    Session& session = *job.session;
    const protocol::StepCommand& command = job.command;
    if (!session.pipeline) {
      PipelineOptions options;
      options.use_current_context = true;
      options.num_threads = config.exact_threads;
      auto pipeline = Pipeline::Create(options);
      if (!pipeline) return PublishStepError(session, command, pipeline.error());
      session.pipeline = std::move(*pipeline);
    }
    // Ingest: the ring up to the commit sequence, checked, then applied all-or-nothing.
    auto updates = session.updates->Drain(command.ring_commit_sequence);
    if (!updates) {
      PublishStepError(session, command, updates.error());
      // A segment its client truncated can never be read again: end the session now.
      if (session.segment->faulted()) {
        CloseSession(session.id, "the client truncated its shared-memory segment", true);
      }
      return;
    }
    if (auto applied = ApplyUpdates(session, *updates); !applied) {
      return PublishStepError(session, command, applied.error());
    }
    session.applied_sequence = session.updates->last_sequence();
    auto result = session.pipeline->Step(command.request);
    if (!result) return PublishStepError(session, command, result.error());
    protocol::StepReplyIds ids{session.id, session.next_reply_id++, command.step_id,
                               session.applied_sequence.load()};
    auto reply = protocol::MakeStepReply(ids, command.request.output, *result);
    if (!reply) return PublishStepError(session, command, reply.error());
    auto bytes = protocol::EncodeStepReplyForTransport(*reply, *session.replies, session.key);
    if (!bytes) return PublishStepError(session, command, bytes.error());
    Publish(session.reply_channel, *bytes);
    // Latency: request received -> reply published.
    const double ms =
        std::chrono::duration<double, std::milli>(Clock::now() - job.received).count();
    {
      std::lock_guard lock(stats_mutex);
      latency.Add(ms);
    }
    {
      std::lock_guard lock(session.latency_mutex);
      session.latency.Add(ms);
    }
    session.steps++;
    session.last_step_id = command.step_id;
    steps_total++;
    spdlog::debug("event=step session={} step={} method={} ms={:.3f} contacts={}", session.id,
                  command.step_id, ToString(command.request.method), ms, result->contacts.size());
  }

  void GlThread(std::promise<Result<std::string>> ready) {
    auto context = GlContext::Create(config.gl_platform);
    if (!context) {
      ready.set_value(context.error());
      return;
    }
    ready.set_value((*context)->renderer());
    for (;;) {
      std::optional<std::pair<int64_t, StepJob>> job;
      std::vector<std::shared_ptr<Session>> closed;
      {
        std::unique_lock lock(mutex);
        work.wait_for(lock, std::chrono::milliseconds(100),
                      [&] { return stop || scheduler.size() > 0 || !to_destroy.empty(); });
        closed.swap(to_destroy);
        job = scheduler.Pop();
        if (!job && closed.empty() && stop) break;  // drained
      }
      // Closed sessions free their GL objects here, on the context's thread.
      for (auto& session : closed) {
        session->pipeline.reset();
        session->segment.reset();
      }
      closed.clear();
      if (!job) continue;
      try {
        RunStep(job->second);
      } catch (const std::exception& e) {
        // One catch per request: a stray exception is an error reply, not a dead daemon.
        PublishStepError(*job->second.session, job->second.command,
                         MakeError(ErrorCode::kInternal, std::string("step failed: ") + e.what()));
      }
    }
    // Free what is left while the context is still current.
    std::lock_guard lock(mutex);
    for (auto& [id, session] : sessions) {
      // Tell the client, so that it does not wait out its timeout for replies that never come.
      PublishError(
          id, &session->key, -1,
          MakeError(ErrorCode::kUnavailable, "session closed: far-daemon is shutting down"), true);
      session->pipeline.reset();
      session->segment.reset();
    }
    sessions.clear();
  }
};

Daemon::Daemon(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Daemon::~Daemon() = default;

Result<std::unique_ptr<Daemon>> Daemon::Create(const DaemonConfig& config) {
  if (auto ok = ValidateDaemonConfig(config); !ok) return ok.error();
  auto impl = std::make_unique<Impl>(config);
  auto bus = protocol::LcmBus::Create(config.lcm_url);
  if (!bus) return bus.error();
  impl->bus = std::move(*bus);
  const int stale = protocol::RemoveStaleSegments();
  if (stale > 0) spdlog::info("event=stale_segments_removed count={}", stale);
  Impl* raw = impl.get();
  impl->bus->Subscribe(
      std::string(protocol::kOpenChannel),
      [raw](std::string_view c, std::span<const uint8_t> b) { raw->OnOpen(c, b); });
  impl->bus->Subscribe(
      std::string(protocol::kSessionRequestChannelPattern),
      [raw](std::string_view c, std::span<const uint8_t> b) { raw->OnSessionRequest(c, b); });
  impl->bus->Subscribe(
      std::string(protocol::kStatusChannel),
      [raw](std::string_view c, std::span<const uint8_t> b) { raw->OnStatus(c, b); });
  return std::unique_ptr<Daemon>(new Daemon(std::move(impl)));
}

Result<void> Daemon::Run(const std::atomic<bool>* stop_flag) {
  Impl& d = *impl_;
  std::promise<Result<std::string>> ready;
  auto renderer = ready.get_future();
  std::thread gl([&d, p = std::move(ready)]() mutable { d.GlThread(std::move(p)); });
  auto made = renderer.get();
  if (!made) {
    gl.join();
    return made.error();
  }
  {
    std::lock_guard lock(d.stats_mutex);
    d.renderer = *made;
  }
  spdlog::info("event=daemon_ready gl_renderer=\"{}\" lcm_url={} max_sessions={}", *made,
               d.config.lcm_url, d.config.max_sessions);
  auto last_reap = Clock::now();
  while (!d.stop && !(stop_flag != nullptr && stop_flag->load())) {
    const bool handled = d.bus->Handle(std::chrono::milliseconds(100));
    // (a signal that stops the daemon also interrupts LCM's wait: not an error)
    if (!handled && !d.stop && !(stop_flag != nullptr && stop_flag->load())) {
      spdlog::error("event=lcm_error lcm_url={}", d.config.lcm_url);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (Clock::now() - last_reap > std::chrono::milliseconds(250)) {
      d.ReapSilentSessions();
      last_reap = Clock::now();
    }
  }
  // Drain: no new steps; the GL thread finishes the queued ones, then frees every session.
  spdlog::info("event=daemon_stopping queued_steps={}", [&] {
    std::lock_guard lock(d.mutex);
    return d.scheduler.size();
  }());
  {
    std::lock_guard lock(d.mutex);
    d.stop = true;
  }
  d.work.notify_all();
  gl.join();
  spdlog::info("event=daemon_stopped steps_total={}", d.steps_total.load());
  return {};
}

void Daemon::Stop() {
  impl_->stop = true;
  impl_->work.notify_all();
}

std::string Daemon::gl_renderer() const {
  std::lock_guard lock(impl_->stats_mutex);
  return impl_->renderer;
}

}  // namespace far::server
