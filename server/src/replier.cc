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
  auto sealed = protocol::SealEncoded(inner, session.id, session.next_reply_id++, session.key);
  if (sealed) Publish(session.uid, session.reply_channel, *sealed);
}

Result<void> Replier::StepReply(Session& session, const far_lcm::step_reply_t& full) {
  auto bytes = protocol::EncodeStepReplyForTransport(full, *session.replies, session.key,
                                                     session.next_reply_id++);
  if (!bytes) return bytes.error();
  Publish(session.uid, session.reply_channel, *bytes);
  return {};
}

void Replier::StepError(Session& session, const protocol::StepCommand& command,
                        const Error& error) {
  stats_.CountError(far::ToString(error.code));
  const protocol::StepReplyIds ids{session.id, command.request_id, command.step_id,
                                   session.applied_sequence.load()};
  if (auto bytes = protocol::EncodeMessage(protocol::MakeStepErrorReply(ids, error)))
    Seal(session, *bytes);
  LogForClient(spdlog::level::info, session.uid, std::string("step_") + far::ToString(error.code),
               "event=step_error session={} step={} code={} reason=\"{}\"", session.id,
               command.step_id, far::ToString(error.code), error.message);
}

void Replier::StepStatus(Session& session, const StepJob& job, std::string_view state,
                         int32_t queue_position, std::optional<Stage> stage) {
  const auto message =
      protocol::MakeStepStatus(session.id, job.command.request_id, job.command.step_id, state,
                               queue_position, stage, MsBetween(job.received, Clock::now()));
  if (auto bytes = protocol::EncodeMessage(message)) Seal(session, *bytes);
}

void Replier::SessionError(Session& session, int64_t request_id, const Error& error,
                           bool session_closed) {
  stats_.CountError(far::ToString(error.code));
  const auto message = protocol::MakeErrorMessage(session.id, request_id, error, session_closed);
  if (auto bytes = protocol::EncodeMessage(message)) Seal(session, *bytes);
}

}  // namespace far::server
