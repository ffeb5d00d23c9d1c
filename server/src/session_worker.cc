#include "session_worker.h"

#include <pthread.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <optional>
#include <thread>

#include "deadline_memory.h"
#include "log_limiter.h"
#include "step_cpu_meter.h"

#include "far/base/thread_pool.h"
#include "far/gpu/gl_lock.h"
#include "far/protocol/convert.h"
#include "far/protocol/shm_reply.h"

namespace far::server {
namespace {

// A step refused for running into the step deadline is tried again after this many deadlines:
// the session spends at most about 1 / (1 + this) of its time on steps that cannot finish.
constexpr int kRecheckDeadlines = 6;

// The threads a heavy session's parallel loops may use: half the daemon's cores (cpu_cores, at
// least one), so that the other half is left to light sessions even before the scheduler
// steps in.
int HeavySessionThreads(const DaemonConfig& config) { return std::max(1, CpuCoresOf(config) / 2); }
// How often a step past heavy_step_ms reads the worker's CPU clock.
constexpr Clock::rep kCpuLookEvery =
    std::chrono::duration_cast<Clock::duration>(std::chrono::milliseconds(1)).count();
// Bytes one contact or distance pair takes in an encoded reply (the larger, a distance pair).
constexpr uint64_t kWireBytesPerPair = 32;

class SessionWorker {
 public:
  SessionWorker(std::shared_ptr<Session> session, const WorkerContext& context)
      : session_(std::move(session)),
        context_(context),
        deadlines_(std::chrono::milliseconds(context.config.step_deadline_ms), kRecheckDeadlines) {}

  void Run() {
    if (clockid_t clock; pthread_getcpuclockid(pthread_self(), &clock) == 0) worker_clock_ = clock;
    StepJob job;
    while (NextJob(&job)) {
      MarkActive(true);
      try {
        RunStep(job);
      } catch (const std::exception& e) {
        // One catch per step: a stray exception is an error reply, not a dead daemon.
        context_.replier.StepError(
            *session_, job.command,
            MakeError(ErrorCode::kInternal, std::string("step failed: ") + e.what()));
      }
      MarkActive(false);
      std::lock_guard lock(session_->mutex);
      session_->ledger.Finish();
    }
    // The pipeline's GL objects and context belong to this thread: free them here.
    session_->pipeline.reset();
    session_->updates.reset();
    session_->replies.reset();
    session_->segment.reset();
    context_.budget.Leave(session_->id);  // its memory is gone: so is its share of the budget
    session_->worker_done = true;
  }

 private:
  // A step starts or ends: the session is not idle (session_idle_timeout_s), and it is the
  // last of its user's sessions that the shared budget closes to make room.
  void MarkActive(bool stepping) {
    session_->stepping = stepping;
    session_->last_active = Clock::now().time_since_epoch().count();
    context_.budget.Touch(session_->id);
  }

  // Waits for the next queued step; false once the session is closing.
  bool NextJob(StepJob* job) {
    std::unique_lock lock(session_->mutex);
    session_->wake.wait(lock, [&] { return session_->closing || !session_->queue.empty(); });
    if (session_->closing) return false;
    *job = std::move(session_->queue.front());
    session_->queue.pop_front();
    session_->ledger.Start(job->command.step_id, job->command.request_id, job->received);
    return true;
  }

  Result<void> EnsurePipeline() {
    if (session_->pipeline) return {};
    PipelineOptions options;
    options.use_gl = context_.use_gl;
    options.platform = context_.config.gl_platform;
    options.gpu_device = context_.config.gpu;
    options.num_threads = context_.config.exact_threads;
    options.cpu_cores = CpuCoresOf(context_.config);
    options.scene_limits = SceneLimitsOf(context_.config);
    options.shared_budget = &context_.budget;
    options.budget_holder = session_->id;
    options.compute_batcher = context_.compute_batcher;
    auto pipeline = Pipeline::Create(options);
    if (!pipeline && options.use_gl) {
      // No GL context for this session (the driver's limit?): the CPU methods still work.
      LogForClient(spdlog::level::warn, session_->uid, "session_without_gl",
                   "event=session_without_gl session={} reason=\"{}\"", session_->id,
                   pipeline.error().message);
      options.use_gl = false;
      pipeline = Pipeline::Create(options);
    }
    if (!pipeline) return pipeline.error();
    session_->pipeline = std::move(*pipeline);
    if (session_->demoted)
      session_->pipeline->SetCpuBackground(HeavySessionThreads(context_.config));
    return {};
  }

  // Drains the ring up to the step's commit sequence and applies the updates all or nothing:
  // a bad update changes nothing, the scene stays as the previous step left it.
  Result<void> Ingest(const protocol::StepCommand& command) {
    auto drained = session_->updates->Drain(command.ring_commit_sequence);
    if (!drained) return drained.error();
    std::vector<SceneUpdate> updates;
    std::vector<uint64_t> sequences;
    updates.reserve(drained->size());
    for (auto& [sequence, update] : *drained) {
      updates.push_back(std::move(update));
      sequences.push_back(sequence);
    }
    auto applied = session_->pipeline->Apply(std::move(updates), [&](size_t i) {
      return "ring record " + std::to_string(sequences[i]) + " (" +
             UpdateName((*drained)[i].update) + ") ";
    });
    if (!applied) return applied;
    session_->applied_sequence = session_->updates->last_sequence();
    session_->num_objects = session_->pipeline->num_objects();
    session_->num_triangles = session_->pipeline->num_triangles();
    return {};
  }

  StepControl ControlFor(const StepJob& job, StepCpuMeter& meter) {
    StepControl control;
    control.cancel = &session_->cancel;
    control.deadline = job.deadline;
    const uint64_t ring = session_->segment->layout().reply_ring_capacity;
    control.max_pairs = static_cast<size_t>(std::min<uint64_t>(
        static_cast<uint64_t>(context_.config.max_reply_pairs), (ring - 4096) / kWireBytesPerPair));
    control.on_stage = [this, &job](Stage stage) {
      {
        std::lock_guard lock(session_->mutex);
        session_->ledger.EnterStage(stage);
      }
      context_.replier.StepStatus(*session_, job, "stage", stage);
    };
    // Past heavy_step_ms of wall time and of the worker's own CPU time, every thread of the
    // step lowers itself at its next check, while the step runs: a step that only ends at its
    // deadline is heavy too.
    const auto started = Clock::now();
    control.slow_after = started + std::chrono::milliseconds(context_.config.heavy_step_ms);
    auto next_look = std::make_shared<std::atomic<Clock::rep>>(0);
    control.on_slow = [this, started, &meter, next_look] {
      if (!session_->demoted.load(std::memory_order_relaxed)) {
        // The worker's CPU clock is a system call: one thread reads it, once a millisecond.
        const Clock::rep now = Clock::now().time_since_epoch().count();
        Clock::rep due = next_look->load(std::memory_order_relaxed);
        if (now < due || !next_look->compare_exchange_strong(due, now + kCpuLookEvery)) return;
        if (!HeavyOnCpu(meter)) return;
        Demote(MsBetween(started, Clock::now()), "running", meter);
      }
      ThreadPool::MoveCallingThreadToBackground();
    };
    control.on_setup_begin = [&meter] { meter.BeginSetup(); };
    control.on_setup_end = [&meter] { meter.EndSetup(); };
    return control;
  }

  // Whether the worker spent heavy_step_ms of CPU time on the step, its covered setup apart.
  // Wall time alone is not enough: contention stretches light steps, CPU time it does not.
  // With wall time alone, 16 clients of one scene whose steps take 2-20 ms alone saw those
  // pass 50 ms now and then on a saturated machine, and were each demoted at a random moment,
  // for good: served 4.6x apart on 2 cores, 1.9x on 16. And one-off work is no step's steady
  // cost: a 3.5 ms step on a 360K-triangle scene, whose first step built its hierarchies, was
  // demoted by that step and served at 4.5 steps/s beside light sessions (30 when not).
  // Without a CPU clock: true.
  bool HeavyOnCpu(const StepCpuMeter& meter) const {
    return !worker_clock_ || meter.SteadyMs() >= context_.config.heavy_step_ms;
  }

  // A heavy session: its pool's threads lower themselves at their next parallel loop too, and
  // its later steps start lowered. Said once.
  void Demote(double ms, const char* step_state, const StepCpuMeter& meter) {
    if (session_->demoted.exchange(true)) return;
    if (session_->pipeline)
      session_->pipeline->SetCpuBackground(HeavySessionThreads(context_.config));
    LogForClient(spdlog::level::info, session_->uid, "session_demoted",
                 "event=session_demoted session={} step_ms={:.1f} step={} nice={} cpu_ms={:.1f} "
                 "setup_ms={:.1f} setup_covered_ms={:.1f}",
                 session_->id, ms, step_state, ThreadPool::kBackgroundNice, meter.SteadyMs(),
                 meter.setup_ms(), meter.covered_ms());
  }

  // How the step ended, for the deadline memory: whether it ran into the daemon's own deadline
  // (not a shorter one the client asked for), and its own running time since `dequeued`: less
  // what this thread waited for other sessions' GL work since `gl_waited_ms` (GlLockWaitedMs).
  DeadlineMemory::StepEnd EndOf(const StepJob& job, const Result<StepResult>& result,
                                Clock::time_point dequeued, double gl_waited_ms) const {
    const bool daemon_deadline =
        job.deadline >= job.received + std::chrono::milliseconds(context_.config.step_deadline_ms);
    DeadlineMemory::StepEnd end;
    end.hit_deadline = !result && result.error().code == ErrorCode::kTimeout && daemon_deadline;
    end.ran = std::chrono::milliseconds(static_cast<int64_t>(MsBetween(dequeued, Clock::now()) -
                                                             (GlLockWaitedMs() - gl_waited_ms)));
    if (!result) end.why = result.error().message;
    return end;
  }

  void RunStep(const StepJob& job) {
    const protocol::StepCommand& command = job.command;
    Replier& replier = context_.replier;
    // The step's own time starts here: its wait in the queue is not its cost.
    const auto dequeued = Clock::now();
    const double gl_waited_ms = GlLockWaitedMs();
    if (Clock::now() >= job.deadline) {
      return replier.StepError(
          *session_, command,
          MakeError(
              ErrorCode::kTimeout,
              "step " + std::to_string(command.step_id) + " waited " +
                  std::to_string(static_cast<int64_t>(MsBetween(job.received, Clock::now()))) +
                  " ms in the queue, past its deadline; it was not run"));
    }
    replier.StepStatus(*session_, job, "started", std::nullopt);
    if (auto ok = EnsurePipeline(); !ok) return replier.StepError(*session_, command, ok.error());
    if (auto ingested = Ingest(command); !ingested) {
      replier.StepError(*session_, command, ingested.error());
      // A segment that faulted can never be read again: end the session now.
      if (session_->segment->faulted())
        context_.close_session(session_->id, "its shared-memory segment cannot be read");
      return;
    }
    const int64_t triangles = session_->pipeline->num_triangles();
    if (auto fits = deadlines_.Check(command.request, triangles, Clock::now()); !fits)
      return replier.StepError(*session_, command, fits.error());
    const auto step_started = Clock::now();
    // The cores this step can count on: the daemon's, over the sessions stepping now.
    if (context_.active != nullptr) {
      const int sessions = context_.active->Stepping(session_->id);
      session_->pipeline->SetCpuShare(static_cast<double>(CpuCoresOf(context_.config)) /
                                      std::max(1, sessions));
    }
    StepCpuMeter meter(worker_clock_, context_.setup_allowance, session_->uid);
    auto result = session_->pipeline->Step(command.request, ControlFor(job, meter));
    deadlines_.Record(command.request, triangles, EndOf(job, result, dequeued, gl_waited_ms),
                      Clock::now());
    if (const double step_ms = MsBetween(step_started, Clock::now());
        step_ms > context_.config.heavy_step_ms && HeavyOnCpu(meter)) {
      ThreadPool::MoveCallingThreadToBackground();
      Demote(step_ms, result ? "finished" : "failed", meter);
    }
    if (!result) return replier.StepError(*session_, command, result.error());
    const protocol::StepReplyIds ids{session_->id, command.request_id, command.step_id,
                                     session_->applied_sequence.load()};
    auto reply = protocol::MakeStepReply(ids, command.request.output, *result);
    if (!reply) return replier.StepError(*session_, command, reply.error());
    // Latency: request received -> reply ready. Counted before the reply goes out, so that a
    // client that has its answer finds the step in the daemon's status.
    const double ms = MsBetween(job.received, Clock::now());
    context_.stats.CountStep(ms, result->stats.method);
    {
      std::lock_guard lock(session_->latency_mutex);
      session_->latency.Add(ms);
    }
    session_->steps++;
    if (auto sent = replier.StepReply(*session_, *reply); !sent)
      return replier.StepError(*session_, command, sent.error());
    LogForClient(spdlog::level::debug, session_->uid, "step",
                 "event=step session={} step={} method={} ms={:.3f} contacts={}", session_->id,
                 command.step_id, result->stats.method, ms, result->contacts.size());
  }

  std::shared_ptr<Session> session_;
  const WorkerContext& context_;
  DeadlineMemory deadlines_;  // the cost of this session's steps, judged before they run
  std::optional<clockid_t> worker_clock_;  // this worker thread's CPU clock
};

}  // namespace

void StartSessionWorker(const std::shared_ptr<Session>& session, const WorkerContext& context) {
  // Under the session's mutex, which the worker takes before it can end and a closer takes to
  // close it: worker_done then means that `worker` is assigned, and ReapWorkers never joins a
  // thread still being moved in.
  std::lock_guard lock(session->mutex);
  if (session->closing) {
    // Closed before it started (a shutdown), perhaps reaped already: a thread started now would
    // outlive the registry. Nothing runs; the segment goes with the last reference.
    session->worker_done = true;
    return;
  }
  session->worker = std::thread([session, &context] { SessionWorker(session, context).Run(); });
}

}  // namespace far::server
