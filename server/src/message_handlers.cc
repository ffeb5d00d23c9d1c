#include "message_handlers.h"

#include <exception>
#include <string>

#include "far_lcm/close_session_t.hpp"
#include "far_lcm/heartbeat_t.hpp"
#include "far_lcm/open_session_reply_t.hpp"
#include "far_lcm/open_session_t.hpp"
#include "far_lcm/status_reply_t.hpp"
#include "far_lcm/status_request_t.hpp"
#include "far_lcm/step_request_t.hpp"
#include <spdlog/spdlog.h>

#include "far/model/version.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/ring_layout.h"

namespace far::server {
namespace {

using protocol::MessageType;
namespace wire = far_lcm;

wire::open_session_reply_t OpenReply(int64_t request_id) {
  wire::open_session_reply_t reply{};
  reply.protocol_version = protocol::kProtocolVersion;
  reply.request_id = request_id;
  return reply;
}

void SetRefusal(wire::open_session_reply_t& reply, const Error& error) {
  reply.status = protocol::ToWireStatus(error.code);
  reply.status_name = far::ToString(error.code);
  reply.message = error.message;
}

// The open reply of an accepted session: where its segment is and what it may send.
void SetAccepted(wire::open_session_reply_t& reply, const Session& session,
                 const DaemonConfig& config) {
  const auto& layout = session.segment->layout();
  const protocol::RingLimits limits = RingLimitsOf(config);
  reply.status = protocol::kWireOk;
  reply.status_name = "ok";
  reply.session_id = session.id;
  reply.shm_name = session.segment->name();
  reply.shm_bytes = static_cast<int64_t>(layout.segment_size);
  reply.ring_layout_version = static_cast<int32_t>(protocol::kLayoutVersion);
  reply.update_ring_bytes = static_cast<int64_t>(layout.update_ring_capacity);
  reply.reply_ring_bytes = static_cast<int64_t>(layout.reply_ring_capacity);
  reply.request_channel = session.request_channel;
  reply.session_reply_channel = session.reply_channel;
  reply.heartbeat_timeout_ms = config.heartbeat_timeout_ms;
  reply.max_objects =
      static_cast<int32_t>(std::min<int64_t>(config.max_objects_per_session, INT32_MAX));
  reply.max_vertices_per_object = static_cast<int32_t>(limits.max_vertices);
  reply.max_triangles_per_object = static_cast<int32_t>(limits.max_triangles);
}

}  // namespace

MessageHandlers::MessageHandlers(const DaemonConfig& config, SessionRegistry& sessions,
                                 Replier& replier, DaemonStats& stats)
    : config_(config), sessions_(sessions), replier_(replier), stats_(stats) {}

void MessageHandlers::Subscribe(protocol::LcmBus& bus,
                                std::function<void(std::string_view channel)> before_handle) {
  auto guarded = [this, before_handle](protocol::LcmBus::Handler handler) {
    return [this, before_handle, handler](std::string_view c, std::span<const uint8_t> b) {
      Guarded(c, b, [&](std::string_view channel, std::span<const uint8_t> bytes) {
        if (before_handle) before_handle(channel);
        handler(channel, bytes);
      });
    };
  };
  bus.Subscribe(std::string(protocol::kOpenChannel),
                guarded([this](auto c, auto b) { OnOpen(c, b); }));
  bus.Subscribe(std::string(protocol::kSessionRequestChannelPattern),
                guarded([this](auto c, auto b) { OnSessionRequest(c, b); }));
  bus.Subscribe(std::string(protocol::kStatusChannel),
                guarded([this](auto c, auto b) { OnStatus(c, b); }));
}

void MessageHandlers::Guarded(std::string_view channel, std::span<const uint8_t> bytes,
                              const protocol::LcmBus::Handler& handler) {
  std::string what;
  try {
    handler(channel, bytes);
    return;
  } catch (const std::exception& e) {
    what = e.what();
  } catch (...) {
    what = "unknown exception";
  }
  // LCM calls handlers from its C code: an exception must never leave this function.
  try {
    const Error error = MakeError(ErrorCode::kInternal, "the daemon failed to handle a message");
    spdlog::error("event=handler_exception channel={} what=\"{}\"", channel, what);
    const auto session_id = protocol::ParseSessionRequestChannel(channel);
    const auto session = session_id ? sessions_.Find(*session_id) : nullptr;
    if (session) {
      replier_.SessionError(session->id, &session->key, -1, error, false);
    } else {
      stats_.CountError(far::ToString(error.code));
    }
  } catch (...) {
    // Out of memory while reporting: nothing more can be done for this message.
  }
}

void MessageHandlers::set_renderer(std::string renderer) {
  std::lock_guard lock(renderer_mutex_);
  renderer_ = std::move(renderer);
}

// A client of another protocol version: tell it so on its reply channel, if it named one.
bool MessageHandlers::AnswerOtherVersion(std::span<const uint8_t> bytes, const Error& error) {
  auto any = protocol::DecodeMessageAnyVersion<wire::open_session_t>(
      bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
  if (!any || !protocol::IsValidOpenReplyChannel(any->reply_channel)) return false;
  wire::open_session_reply_t reply = OpenReply(any->request_id);
  SetRefusal(reply, error);
  stats_.CountError(reply.status_name);
  if (auto out = protocol::EncodeMessage(reply)) replier_.Publish(any->reply_channel, *out);
  return true;
}

void MessageHandlers::OnOpen(std::string_view channel, std::span<const uint8_t> bytes) {
  auto message = protocol::DecodeMessage<wire::open_session_t>(bytes.data(), bytes.size(),
                                                               protocol::kMaxControlMessageBytes);
  if (!message && message.error().code == ErrorCode::kVersionMismatch &&
      AnswerOtherVersion(bytes, message.error())) {
    return;
  }
  if (!message) return replier_.Reject(channel, message.error());
  auto params = protocol::ValidateOpenSession(*message);
  // Answer only on a well-formed reply channel: never publish where a client did not ask.
  if (!params && !protocol::IsValidOpenReplyChannel(message->reply_channel))
    return replier_.Reject(channel, params.error());
  wire::open_session_reply_t reply = OpenReply(message->request_id);
  auto session =
      params ? sessions_.Open(*params) : Result<std::shared_ptr<Session>>(params.error());
  if (session) {
    SetAccepted(reply, **session, config_);
  } else {
    SetRefusal(reply, session.error());
    stats_.CountError(reply.status_name);
    spdlog::warn("event=open_refused client=\"{}\" reason=\"{}\"", message->client_name,
                 ToString(session.error()));
  }
  if (auto out = protocol::EncodeMessage(reply)) replier_.Publish(message->reply_channel, *out);
  if (session) {
    spdlog::info("event=session_open session={} client=\"{}\" shm={}", (*session)->id,
                 (*session)->client_name, (*session)->segment->name());
  }
}

void MessageHandlers::CloseSession(int64_t id, const std::string& reason, bool tell_client) {
  auto closed = sessions_.Close(id);
  if (!closed) return;
  for (const StepJob& job : closed->pending) {
    replier_.StepError(*closed->session, job.command.step_id,
                       MakeError(ErrorCode::kUnavailable, "session closed: " + reason));
  }
  if (tell_client) {
    replier_.SessionError(id, &closed->session->key, -1,
                          MakeError(ErrorCode::kTimeout, "session closed: " + reason), true);
  }
  spdlog::info("event=session_close session={} reason=\"{}\"", id, reason);
}

// Decodes, authenticates and replay-checks a session message. On failure it is rejected (with
// an unsigned error_t on the session's reply channel) and nullopt is returned.
template <typename T>
std::optional<std::pair<T, std::shared_ptr<Session>>> MessageHandlers::AuthenticatedMessage(
    std::string_view channel, int64_t channel_session, std::span<const uint8_t> bytes) {
  auto message =
      protocol::DecodeMessage<T>(bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
  if (!message) {
    replier_.Reject(channel, message.error(), channel_session);
    return std::nullopt;
  }
  if (message->session_id != channel_session) {
    replier_.Reject(channel,
                    MakeError(ErrorCode::kInvalidArgument,
                              "session_id: " + std::to_string(message->session_id) +
                                  " does not match channel " + std::string(channel)),
                    channel_session, message->request_id);
    return std::nullopt;
  }
  auto session = sessions_.Find(channel_session);
  if (!session) {
    replier_.Reject(channel,
                    MakeError(ErrorCode::kNotFound,
                              "session_id: no open session " + std::to_string(channel_session)),
                    channel_session, message->request_id, /*session_closed=*/true);
    return std::nullopt;
  }
  if (auto ok = protocol::VerifyEncoded(bytes, session->key); !ok) {
    replier_.Reject(channel, ok.error(), channel_session, message->request_id);
    return std::nullopt;
  }
  if (message->request_id <= session->last_request_id) {
    replier_.Reject(
        channel,
        MakeError(ErrorCode::kInvalidArgument,
                  "request_id: " + std::to_string(message->request_id) +
                      " is not above the last one (" + std::to_string(session->last_request_id) +
                      "): replayed or reordered"),
        channel_session, message->request_id, /*session_closed=*/false, &session->key);
    return std::nullopt;
  }
  session->last_request_id = message->request_id;
  session->last_heard_ms = NowMs();
  return std::make_pair(std::move(*message), std::move(session));
}

void MessageHandlers::OnStepRequest(std::string_view channel, int64_t channel_session,
                                    std::span<const uint8_t> bytes) {
  auto opened = AuthenticatedMessage<wire::step_request_t>(channel, channel_session, bytes);
  if (!opened) return;
  auto& [message, session] = *opened;
  auto command = protocol::ValidateStepRequest(message);
  if (command && command->request.resolution > config_.max_resolution) {
    command = MakeError(ErrorCode::kLimitExceeded,
                        "resolution: " + std::to_string(command->request.resolution) +
                            " is over this daemon's max_resolution " +
                            std::to_string(config_.max_resolution));
  }
  if (!command) return replier_.StepError(*session, message.step_id, command.error());
  const int64_t step_id = command->step_id;
  if (auto queued = sessions_.Queue(StepJob{session, *command, std::chrono::steady_clock::now()});
      !queued) {
    replier_.StepError(*session, step_id, queued.error());
  }
}

void MessageHandlers::OnHeartbeat(std::string_view channel, int64_t channel_session,
                                  std::span<const uint8_t> bytes) {
  auto opened = AuthenticatedMessage<wire::heartbeat_t>(channel, channel_session, bytes);
  if (!opened) return;
  auto& [message, session] = *opened;
  wire::heartbeat_t reply = message;
  reply.request_id = session->next_reply_id++;
  reply.last_applied_sequence = static_cast<int64_t>(session->applied_sequence.load());
  reply.last_step_id = session->last_step_id.load();
  if (auto out = protocol::EncodeSigned(reply, session->key))
    replier_.Publish(session->reply_channel, *out);
}

void MessageHandlers::OnSessionRequest(std::string_view channel, std::span<const uint8_t> bytes) {
  auto channel_session = protocol::ParseSessionRequestChannel(channel);
  if (!channel_session)
    return replier_.Reject(channel, MakeError(ErrorCode::kInvalidArgument, "unknown channel"));
  auto type = protocol::IdentifyMessage(bytes.data(), bytes.size());
  if (!type) return replier_.Reject(channel, type.error(), *channel_session);
  switch (*type) {
    case MessageType::kStepRequest:
      return OnStepRequest(channel, *channel_session, bytes);
    case MessageType::kHeartbeat:
      return OnHeartbeat(channel, *channel_session, bytes);
    case MessageType::kCloseSession: {
      auto opened = AuthenticatedMessage<wire::close_session_t>(channel, *channel_session, bytes);
      if (opened) CloseSession(opened->second->id, "closed by the client", false);
      return;
    }
    default:
      return replier_.Reject(
          channel,
          MakeError(ErrorCode::kInvalidArgument, std::string(protocol::ToString(*type)) +
                                                     " is not a client-to-daemon session message"),
          *channel_session);
  }
}

void MessageHandlers::OnStatus(std::string_view channel, std::span<const uint8_t> bytes) {
  auto message = protocol::DecodeMessage<wire::status_request_t>(bytes.data(), bytes.size(),
                                                                 protocol::kMaxControlMessageBytes);
  if (!message) return replier_.Reject(channel, message.error());
  wire::status_reply_t reply{};
  reply.protocol_version = protocol::kProtocolVersion;
  reply.request_id = message->request_id;
  reply.daemon_version = kVersion;
  {
    std::lock_guard lock(renderer_mutex_);
    reply.gl_renderer = renderer_.empty() ? "none" : renderer_;
  }
  const DaemonStats::Snapshot stats = stats_.Read();
  reply.latency_p50_ms = stats.p50_ms;
  reply.latency_p90_ms = stats.p90_ms;
  reply.latency_p99_ms = stats.p99_ms;
  reply.latency_max_ms = stats.max_ms;
  reply.latency_samples = stats.latency_samples;
  for (const auto& [kind, count] : stats.errors_by_kind) {
    reply.error_kind.push_back(kind);
    reply.error_count.push_back(count);
  }
  reply.num_error_kinds = static_cast<int32_t>(reply.error_kind.size());
  reply.uptime_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                        std::chrono::steady_clock::now() - started_)
                        .count();
  reply.max_sessions = config_.max_sessions;
  reply.steps_total = stats.steps_total;
  reply.errors_total = stats.errors_total;
  reply.rejected_messages_total = stats.rejected_total;
  for (const auto& session : sessions_.Sessions()) {
    reply.session_id.push_back(session->id);
    reply.session_client_name.push_back(session->client_name);
    reply.session_steps.push_back(session->steps);
    reply.session_objects.push_back(session->num_objects);
    std::lock_guard lock(session->latency_mutex);
    reply.session_latency_p50_ms.push_back(session->latency.Quantile(0.5));
    reply.session_latency_p99_ms.push_back(session->latency.Quantile(0.99));
  }
  reply.num_sessions = static_cast<int32_t>(reply.session_id.size());
  if (auto out = protocol::EncodeMessage(reply))
    replier_.Publish(std::string(protocol::kStatusReplyChannel), *out);
}

void MessageHandlers::ReapSilentSessions() {
  for (int64_t id : sessions_.Silent(NowMs(), config_.heartbeat_timeout_ms)) {
    CloseSession(id, "no heartbeat for " + std::to_string(config_.heartbeat_timeout_ms) + " ms",
                 true);
  }
}

}  // namespace far::server
