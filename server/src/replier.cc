#include "replier.h"

#include <spdlog/spdlog.h>

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/message.h"

namespace far::server {

void Replier::Publish(const std::string& channel, std::span<const uint8_t> bytes) {
  if (auto ok = bus_.Publish(channel, bytes); !ok) {
    spdlog::error("event=publish_failed channel={} reason=\"{}\"", channel, ok.error().message);
  }
}

void Replier::PublishErrorMessage(int64_t session_id, const protocol::SessionKey* key,
                                  int64_t request_id, const Error& error, bool session_closed) {
  auto message = protocol::MakeErrorMessage(session_id, request_id, error, session_closed);
  auto bytes =
      key != nullptr ? protocol::EncodeSigned(message, *key) : protocol::EncodeMessage(message);
  if (bytes) Publish(protocol::SessionReplyChannel(session_id), *bytes);
}

void Replier::SessionError(int64_t session_id, const protocol::SessionKey* key, int64_t request_id,
                           const Error& error, bool session_closed) {
  stats_.CountError(far::ToString(error.code));
  PublishErrorMessage(session_id, key, request_id, error, session_closed);
}

void Replier::StepError(Session& session, int64_t step_id, const Error& error) {
  stats_.CountError(far::ToString(error.code));
  protocol::StepReplyIds ids{session.id, session.next_reply_id++, step_id,
                             session.applied_sequence.load()};
  auto bytes = protocol::EncodeSigned(protocol::MakeStepErrorReply(ids, error), session.key);
  if (bytes) Publish(session.reply_channel, *bytes);
  spdlog::info("event=step_error session={} step={} code={} reason=\"{}\"", session.id, step_id,
               far::ToString(error.code), error.message);
}

void Replier::Reject(std::string_view channel, const Error& error, int64_t reply_session,
                     int64_t request_id, bool session_closed, const protocol::SessionKey* key) {
  stats_.CountRejected(far::ToString(error.code));
  spdlog::warn("event=message_rejected channel={} reason=\"{}\"", channel, ToString(error));
  if (reply_session > 0) PublishErrorMessage(reply_session, key, request_id, error, session_closed);
}

}  // namespace far::server
