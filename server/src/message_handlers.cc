#include "message_handlers.h"

#include <algorithm>
#include <exception>
#include <string>

#include "log_limiter.h"

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/session_auth.h"

namespace far::server {

MessageHandlers::MessageHandlers(const DaemonConfig& config, SessionRegistry& sessions,
                                 Replier& replier, DaemonStats& stats)
    : config_(config),
      sessions_(sessions),
      replier_(replier),
      stats_(stats),
      prefix_(protocol::ChannelPrefix(config.name)) {}

void MessageHandlers::Subscribe(protocol::LcmBus& bus,
                                std::function<void(std::string_view channel)> before_handle) {
  bus.Subscribe(protocol::SessionRequestChannelPattern(prefix_),
                [this, before_handle](std::string_view c, std::span<const uint8_t> b) {
                  Guarded(c, b, [&](std::string_view channel, std::span<const uint8_t> bytes) {
                    if (before_handle) before_handle(channel);
                    OnSessionRequest(channel, bytes);
                  });
                });
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
    stats_.CountError(far::ToString(ErrorCode::kInternal));
    LogForClient(spdlog::level::err, LogLimiter::kNoUser, "handler_exception",
                 "event=handler_exception channel={} what=\"{}\"", channel, what);
  } catch (...) {
    // Out of memory while reporting: nothing more can be done for this message.
  }
}

void MessageHandlers::OnSessionRequest(std::string_view channel, std::span<const uint8_t> bytes) {
  // Everything up to the tag check costs a few microseconds and answers nobody.
  auto drop = [&](const Error& error) {
    stats_.CountRejected(far::ToString(error.code), error.message);
  };
  const auto channel_session = protocol::ParseSessionRequestChannel(prefix_, channel);
  if (!channel_session) return drop(MakeError(ErrorCode::kInvalidArgument, "unknown channel"));
  auto message = protocol::DecodeMessage<far_lcm::step_request_t>(
      bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
  if (!message) return drop(message.error());
  if (message->session_id != *channel_session)
    return drop(MakeError(ErrorCode::kInvalidArgument, "session_id does not match the channel"));
  auto session = sessions_.Find(*channel_session);
  if (!session) return drop(MakeError(ErrorCode::kNotFound, "no such session"));
  if (auto ok = protocol::VerifyEncoded(bytes, session->key); !ok) return drop(ok.error());
  if (message->request_id <= session->last_request_id) {
    return drop(MakeError(ErrorCode::kInvalidArgument, "request_id replayed or reordered"));
  }
  session->last_request_id = message->request_id;
  // Authenticated: from here on the client hears why its request failed. A probe, or a step
  // asked for again, is answered from what the session keeps; no step runs twice.
  if (protocol::IsProbe(*message) || !TakeStep(*session, message->step_id))
    return AnswerAgain(*session, *message);
  auto command = protocol::ValidateStepRequest(*message);
  if (command && command->request.resolution > config_.max_resolution) {
    command = MakeError(ErrorCode::kLimitExceeded,
                        "resolution: " + std::to_string(command->request.resolution) +
                            " is over this daemon's max_resolution " +
                            std::to_string(config_.max_resolution));
  }
  if (!command) {
    protocol::StepCommand ids;
    ids.request_id = message->request_id;
    ids.step_id = message->step_id;
    return replier_.StepError(*session, ids, command.error());
  }
  Queue(*session, std::move(*command));
}

bool MessageHandlers::TakeStep(Session& session, int64_t step_id) {
  std::lock_guard lock(session.mutex);
  return session.ledger.Take(step_id);
}

void MessageHandlers::AnswerAgain(Session& session, const far_lcm::step_request_t& message) {
  if (!session.repeat_rate.Allow()) {
    return stats_.CountRejected(
        far::ToString(ErrorCode::kBusy),
        "session " + std::to_string(session.id) + " asks again faster than " +
            FormatRate(Session::kRepeatsPerSecond) + "/s (probes and repeated steps)");
  }
  if (protocol::IsProbe(message)) return replier_.Heard(session, message.request_id);
  StepRecall recall;
  {
    std::lock_guard lock(session.mutex);
    recall = session.ledger.Recall(message.step_id, session.queue);
  }
  replier_.Again(session, message.request_id, message.step_id, recall);
}

void MessageHandlers::Queue(Session& session, protocol::StepCommand command) {
  const auto now = Clock::now();
  const int wait_ms = command.timeout_ms > 0
                          ? std::min(command.timeout_ms, config_.step_deadline_ms)
                          : config_.step_deadline_ms;
  StepJob job{std::move(command), now, now + std::chrono::milliseconds(wait_ms)};
  // The rate is for requests sent without waiting: one that finds none of the session's steps
  // waiting in its queue (a client that waits for each answer, however fast its steps) is
  // never refused for it, and takes no token.
  bool others_waiting;
  {
    std::lock_guard lock(session.mutex);
    others_waiting = !session.queue.empty();
  }
  if (others_waiting && !session.request_rate.Allow(now)) {
    return replier_.StepError(
        session, job.command,
        MakeError(ErrorCode::kBusy, "session is over its request rate (" +
                                        FormatRate(config_.max_requests_per_second) + "/s)"));
  }
  {
    std::lock_guard lock(session.mutex);
    if (session.closing) return;
    if (session.queue.size() < static_cast<size_t>(config_.max_queued_per_session)) {
      // Said before the worker can take it, so that "queued" always comes before "started".
      replier_.QueuedStatus(session, job, static_cast<int32_t>(session.queue.size()),
                            !session.queue.empty() || session.ledger.running());
      session.queue.push_back(std::move(job));
      session.last_active = now.time_since_epoch().count();  // not idle (IdleSessions)
      session.wake.notify_one();
      return;
    }
  }
  replier_.StepError(
      session, job.command,
      MakeError(ErrorCode::kBusy, "session has " + std::to_string(config_.max_queued_per_session) +
                                      " steps pending (its limit)"));
}

}  // namespace far::server
