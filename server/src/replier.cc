#include "replier.h"

#include "log_limiter.h"

#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/shm_reply.h"

namespace far::server {

void Replier::Publish(uid_t uid, const std::string& channel, std::span<const uint8_t> bytes) {
  if (auto ok = bus_.Publish(channel, bytes); !ok) {
    LogForClient(spdlog::level::err, uid, "publish_failed",
                 "event=publish_failed channel={} reason=\"{}\"", channel, ok.error().message);
  }
}

void Replier::Seal(Session& session, std::span<const uint8_t> inner) {
  std::lock_guard lock(session.publish_mutex);
  auto sealed = protocol::SealEncoded(inner, session.id, session.next_reply_id++, session.key);
  if (sealed) Publish(session.uid, session.reply_channel, *sealed);
}

void Replier::Answer(Session& session, int64_t step_id, std::vector<uint8_t> inner) {
  // Kept first: a repeat that comes as soon as the answer is out finds it.
  {
    std::lock_guard lock(session.mutex);
    session.ledger.Keep(step_id, inner);
  }
  Seal(session, inner);
}

Result<void> Replier::StepReply(Session& session, const far_lcm::step_reply_t& full) {
  auto inner = protocol::EncodeStepReplyInner(full, *session.replies);
  if (!inner) return inner.error();
  Answer(session, full.step_id, std::move(*inner));
  return {};
}

void Replier::StepError(Session& session, const protocol::StepCommand& command,
                        const Error& error) {
  stats_.CountError(far::ToString(error.code));
  const protocol::StepReplyIds ids{session.id, command.request_id, command.step_id,
                                   session.applied_sequence.load()};
  if (auto bytes = protocol::EncodeMessage(protocol::MakeStepErrorReply(ids, error)))
    Answer(session, command.step_id, std::move(*bytes));
  LogForClient(spdlog::level::info, session.uid, std::string("step_") + far::ToString(error.code),
               "event=step_error session={} step={} code={} reason=\"{}\"", session.id,
               command.step_id, far::ToString(error.code), error.message);
}

void Replier::Status(Session& session, int64_t request_id, int64_t step_id, std::string_view state,
                     int32_t queue_position, std::optional<Stage> stage,
                     Clock::time_point received) {
  const auto message =
      protocol::MakeStepStatus(session.id, request_id, step_id, state, queue_position, stage,
                               MsBetween(received, Clock::now()));
  if (auto bytes = protocol::EncodeMessage(message)) Seal(session, *bytes);
}

void Replier::StepStatus(Session& session, const StepJob& job, std::string_view state,
                         std::optional<Stage> stage) {
  if (Clock::now() - job.received < status_after_) return;
  Status(session, job.command.request_id, job.command.step_id, state, 0, stage, job.received);
}

void Replier::QueuedStatus(Session& session, const StepJob& job, int32_t queue_position,
                           bool behind_another) {
  if (!behind_another && Clock::now() - job.received < status_after_) return;
  Status(session, job.command.request_id, job.command.step_id, "queued", queue_position,
         std::nullopt, job.received);
}

void Replier::Again(Session& session, int64_t request_id, int64_t step_id,
                    const StepRecall& recall) {
  switch (recall.kind) {
    case StepRecall::Kind::kAnswered:
      return Seal(session, recall.reply);
    case StepRecall::Kind::kRunning:
      return Status(session, recall.request_id, step_id, recall.stage ? "stage" : "started", 0,
                    recall.stage, recall.received);
    case StepRecall::Kind::kQueued:
      return Status(session, recall.request_id, step_id, "queued", recall.queue_position,
                    std::nullopt, recall.received);
    case StepRecall::Kind::kForgotten:
      break;
  }
  const Error error = MakeError(
      ErrorCode::kNotFound, "step " + std::to_string(step_id) + " was answered before the last " +
                                std::to_string(StepLedger::kMaxKept) +
                                " answers this daemon keeps per session; it is not run again");
  stats_.CountError(far::ToString(error.code));
  const protocol::StepReplyIds ids{session.id, request_id, step_id,
                                   session.applied_sequence.load()};
  if (auto bytes = protocol::EncodeMessage(protocol::MakeStepErrorReply(ids, error)))
    Seal(session, *bytes);
}

void Replier::Heard(Session& session, int64_t request_id) {
  Status(session, request_id, -1, protocol::kHeardState, 0, std::nullopt, Clock::now());
}

void Replier::SessionError(Session& session, int64_t request_id, const Error& error,
                           bool session_closed) {
  stats_.CountError(far::ToString(error.code));
  const auto message = protocol::MakeErrorMessage(session.id, request_id, error, session_closed);
  if (auto bytes = protocol::EncodeMessage(message)) Seal(session, *bytes);
}

}  // namespace far::server
