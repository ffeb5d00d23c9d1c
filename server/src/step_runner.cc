#include "step_runner.h"

#include <chrono>
#include <exception>
#include <string>

#include <spdlog/spdlog.h>

#include "far/gpu/gl_context.h"
#include "far/protocol/convert.h"
#include "far/protocol/shm_reply.h"

namespace far::server {

// Drains the ring up to the step's commit sequence and applies the updates all or nothing:
// a bad update changes nothing, the scene stays as the previous step left it.
Result<void> StepRunner::Ingest(Session& session, const protocol::StepCommand& command) {
  auto drained = session.updates->Drain(command.ring_commit_sequence);
  if (!drained) return drained.error();
  std::vector<SceneUpdate> updates;
  std::vector<uint64_t> sequences;
  updates.reserve(drained->size());
  for (auto& [sequence, update] : *drained) {
    updates.push_back(std::move(update));
    sequences.push_back(sequence);
  }
  auto applied = session.pipeline->Apply(std::move(updates), [&](size_t i) {
    return "ring record " + std::to_string(sequences[i]) + " (" + UpdateName((*drained)[i].update) +
           ") ";
  });
  if (!applied) return applied;
  session.applied_sequence = session.updates->last_sequence();
  session.num_objects = session.pipeline->num_objects();
  return {};
}

void StepRunner::RunStep(StepJob& job) {
  Session& session = *job.session;
  const protocol::StepCommand& command = job.command;
  if (!session.pipeline) {
    PipelineOptions options;
    options.use_current_context = true;
    options.num_threads = config_.exact_threads;
    options.scene_limits = SceneLimitsOf(config_);
    auto pipeline = Pipeline::Create(options);
    if (!pipeline) return replier_.StepError(session, command.step_id, pipeline.error());
    session.pipeline = std::move(*pipeline);
  }
  if (auto ingested = Ingest(session, command); !ingested) {
    replier_.StepError(session, command.step_id, ingested.error());
    // A segment its client truncated can never be read again: end the session now.
    if (session.segment->faulted()) {
      handlers_.CloseSession(session.id, "the client truncated its shared-memory segment", true);
    }
    return;
  }
  auto result = session.pipeline->Step(command.request);
  if (!result) return replier_.StepError(session, command.step_id, result.error());
  protocol::StepReplyIds ids{session.id, session.next_reply_id++, command.step_id,
                             session.applied_sequence.load()};
  auto reply = protocol::MakeStepReply(ids, command.request.output, *result);
  if (!reply) return replier_.StepError(session, command.step_id, reply.error());
  auto bytes = protocol::EncodeStepReplyForTransport(*reply, *session.replies, session.key);
  if (!bytes) return replier_.StepError(session, command.step_id, bytes.error());
  replier_.Publish(session.reply_channel, *bytes);
  // Latency: request received -> reply published.
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - job.received)
          .count();
  stats_.CountStep(ms);
  {
    std::lock_guard lock(session.latency_mutex);
    session.latency.Add(ms);
  }
  session.steps++;
  session.last_step_id = command.step_id;
  spdlog::debug("event=step session={} step={} method={} ms={:.3f} contacts={}", session.id,
                command.step_id, ToString(command.request.method), ms, result->contacts.size());
}

// Every session left at shutdown: its client is told, its GL objects freed while the context
// is still current.
void StepRunner::ShutDown() {
  for (auto& session : sessions_.TakeAll()) {
    replier_.SessionError(
        session->id, &session->key, -1,
        MakeError(ErrorCode::kUnavailable, "session closed: far-daemon is shutting down"), true);
    session->pipeline.reset();
    session->segment.reset();
  }
}

void StepRunner::Run(std::promise<Result<std::string>> ready) {
  auto context = GlContext::Create(config_.gl_platform);
  if (!context) {
    ready.set_value(context.error());
    return;
  }
  ready.set_value((*context)->renderer());
  for (;;) {
    SessionRegistry::Work work = sessions_.WaitForWork(std::chrono::milliseconds(100));
    // Closed sessions free their GL objects here, on the context's thread.
    for (auto& session : work.freed) {
      session->pipeline.reset();
      session->segment.reset();
    }
    if (work.done) break;
    if (!work.job) continue;
    try {
      RunStep(*work.job);
    } catch (const std::exception& e) {
      // One catch per request: a stray exception is an error reply, not a dead daemon.
      replier_.StepError(*work.job->session, work.job->command.step_id,
                         MakeError(ErrorCode::kInternal, std::string("step failed: ") + e.what()));
    }
  }
  ShutDown();
}

}  // namespace far::server
