#include "daemon.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon_stats.h"
#include "gpu_cost_cache.h"
#include "log_limiter.h"
#include "message_handlers.h"
#include "metrics_export.h"
#include "replier.h"
#include "session_registry.h"
#include "session_worker.h"
#include "socket_server.h"
#include "status_reply.h"
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "far/base/gpu_identity.h"
#include "far/gpu/compute_batcher.h"
#include "far/gpu/gl_context.h"
#include "far/model/scene_budget.h"
#include "far/pipeline/pipeline.h"
#include "far/protocol/channels.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/local_socket.h"

namespace far::server {
namespace {

// Says where the daemon stands with the kernel's OOM killer (/proc/self/oom_score_adj, -1000 to
// 1000, lower is spared longer). Only a privileged parent can lower it (the service unit's
// OOMScoreAdjust=-500); the daemon itself could only raise it (docs/daemon.md, "Memory and the OOM
// killer").
void LogOomScoreAdj() {
  std::ifstream file("/proc/self/oom_score_adj");
  int adj = 0;
  if (!(file >> adj)) return;
  if (adj < 0) {
    spdlog::info("event=oom_score_adj value={}", adj);
  } else {
    spdlog::info(
        "event=oom_score_adj value={} message=\"the OOM killer may choose far-daemon when others "
        "fill the memory; its service unit sets OOMScoreAdjust=-500\"",
        adj);
  }
}

// The EGL device a scheduler's name for a GPU (far-daemon --gpu-id) stands for.
Result<int> EglDeviceNamed(const std::string& gpu_id) {
  std::string seen;
  for (const GlContext::Device& device : GlContext::ListDevices()) {
    const std::vector<std::string> names = GpuIdentifiers(device.drm_device_file);
    if (NamesGpu(gpu_id, names)) return device.index;
    std::string list;
    for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
    seen += "\n  - " + device.description + ": " + (list.empty() ? "no names" : list);
  }
  return MakeError(ErrorCode::kUnavailable,
                   "--gpu-id " + gpu_id + ": no EGL device has that name; the devices are:" +
                       (seen.empty() ? std::string(" none (no EGL device platform)") : seen));
}

// The names clients may know this daemon's GPU by: its EGL device's, then the configured ones.
std::vector<std::string> ServedGpuNames(const DaemonConfig& config,
                                        const std::string& drm_device_file) {
  std::vector<std::string> names = GpuIdentifiers(drm_device_file);
  for (const std::string& name : config.serves_gpus)
    if (!NamesGpu(name, names)) names.push_back(name);
  return names;
}

}  // namespace

struct Daemon::Impl {
  DaemonConfig config;
  std::unique_ptr<protocol::LcmBus> bus;
  std::unique_ptr<protocol::LocalListener> listener;
  DaemonStats stats;
  SharedSceneBudget budget{BudgetTotalsOf(config)};
  // Before the sessions: their pipelines' gpu steps go to it until they end.
  std::unique_ptr<ComputeBatcher> compute_batcher;
  SessionRegistry sessions{config, budget};
  SetupAllowance setup_allowance{config.setup_allowance_ms};
  std::unique_ptr<Replier> replier;
  std::unique_ptr<MessageHandlers> handlers;
  ActiveSessions active_sessions;  // before workers: they point at it
  std::unique_ptr<WorkerContext> workers;
  std::unique_ptr<StatusSources> status;
  std::atomic<bool> stop{false};
  const std::chrono::steady_clock::time_point created = std::chrono::steady_clock::now();
  mutable std::mutex renderer_mutex;
  std::string renderer;
  bool batcher_context_fails = false;  // DaemonTestHooks

  explicit Impl(const DaemonConfig& c) : config(c) {}
  bool Stopping(const std::atomic<bool>* stop_flag) const {
    return stop || (stop_flag != nullptr && stop_flag->load());
  }
  void ServeMessages(const std::atomic<bool>* stop_flag);
  void CloseSession(int64_t id, const std::string& reason);
  void EndSession(int64_t id, const Error& why);
  void ExpireIdleSessions();
  void CloseEverySession();
  void StartBatcher(int gpu);
  Clock::time_point next_idle_check;
};

Daemon::Daemon(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Daemon::~Daemon() = default;

Result<std::unique_ptr<Daemon>> Daemon::Create(const DaemonConfig& config, DaemonTestHooks hooks) {
  if (auto ok = ValidateDaemonConfig(config); !ok) return ok.error();
  auto impl = std::make_unique<Impl>(config);
  impl->batcher_context_fails = hooks.batcher_context_fails;
  auto bus = protocol::LcmBus::Create(config.lcm_url);
  if (!bus) return bus.error();
  impl->bus = std::move(*bus);
  auto listener = protocol::LocalListener::Listen(SocketPathOf(config));
  if (!listener) return listener.error();
  impl->listener = std::move(*listener);
  // Another user took /tmp/far-<uid>: the socket is in $HOME instead, where clients look too.
  if (const auto user = protocol::PerUserSocketDirectory();
      config.socket_path.empty() && !user.tmp_taken.empty() &&
      protocol::DefaultSocketDirectory() == user.path) {
    spdlog::warn("event=socket_directory_taken reason=\"{}\" socket={}", user.tmp_taken,
                 SocketPathOf(config));
  }
  impl->replier = std::make_unique<Replier>(*impl->bus, impl->stats,
                                            std::chrono::milliseconds(config.status_after_ms));
  impl->handlers =
      std::make_unique<MessageHandlers>(impl->config, impl->sessions, *impl->replier, impl->stats);
  impl->handlers->Subscribe(*impl->bus, std::move(hooks.before_message));
  Impl* raw = impl.get();
  impl->budget.OnReclaim([raw](int64_t id, const Error& why) { raw->EndSession(id, why); });
  impl->workers = std::make_unique<WorkerContext>(WorkerContext{
      impl->config, *impl->replier, impl->stats, impl->budget, impl->setup_allowance, true,
      [raw](int64_t id, const std::string& reason) { raw->CloseSession(id, reason); },
      &impl->active_sessions});
  return std::unique_ptr<Daemon>(new Daemon(std::move(impl)));
}

// The daemon ends a session: its client is told (sealed, so it trusts it), then the worker
// ends and the socket server closes the connection.
void Daemon::Impl::CloseSession(int64_t id, const std::string& reason) {
  EndSession(id, MakeError(ErrorCode::kUnavailable, "session closed: " + reason));
}

void Daemon::Impl::EndSession(int64_t id, const Error& why) {
  auto session = sessions.Find(id);
  if (!session) return;
  // Told before the session closes: the connection closes only after, so the client hears why
  // before it sees its end of the connection go.
  replier->SessionError(*session, -1, why, true);
  if (!sessions.Close(id)) return;
  LogForClient(spdlog::level::info, session->uid, "session_close",
               "event=session_close session={} uid={} reason=\"{}\"", id, session->uid,
               why.message);
}

// Closes the sessions that have not stepped for session_idle_timeout_s (checked 4 times a
// second, on the LCM thread: whether or not their connections stay open).
void Daemon::Impl::ExpireIdleSessions() {
  const auto now = Clock::now();
  if (config.session_idle_timeout_s <= 0 || now < next_idle_check) return;
  next_idle_check = now + std::chrono::milliseconds(250);
  const auto timeout = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config.session_idle_timeout_s));
  for (int64_t id : sessions.IdleSessions(now, timeout)) {
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%g", config.session_idle_timeout_s);
    EndSession(id, MakeError(ErrorCode::kUnavailable,
                             std::string("session expired after ") + seconds +
                                 " s without steps (far-daemon's session_idle_timeout_s)"));
  }
}

// The gpu method's batcher, on a GL context of its own: where a driver gives no second one,
// each session issues its own gpu steps instead.
void Daemon::Impl::StartBatcher(int gpu) {
  auto batcher = batcher_context_fails
                     ? Result<std::unique_ptr<ComputeBatcher>>(
                           MakeError(ErrorCode::kUnavailable, "no second context (test hook)"))
                     : ComputeBatcher::Create(config.gl_platform, gpu);
  if (!batcher) {
    spdlog::warn("event=gpu_batch_unavailable reason=\"{}\"", batcher.error().message);
    return;
  }
  compute_batcher = std::move(*batcher);
  workers->compute_batcher = compute_batcher.get();
}

void Daemon::Impl::CloseEverySession() {
  for (auto& session : sessions.CloseAll()) {
    replier->SessionError(
        *session, -1,
        MakeError(ErrorCode::kUnavailable, "session closed: far-daemon is shutting down"), true);
  }
  sessions.ReapWorkers(/*wait=*/true);
}

// The LCM thread: handles step requests until stopped.
void Daemon::Impl::ServeMessages(const std::atomic<bool>* stop_flag) {
  while (!Stopping(stop_flag)) {
    ExpireIdleSessions();
    const bool handled = bus->Handle(std::chrono::milliseconds(100));
    // The summaries of floods that stopped (at most once a second).
    ClientLogLimiter().Flush();
    // (a signal that stops the daemon also interrupts LCM's wait: not an error)
    if (!handled && !Stopping(stop_flag)) {
      LogForClient(spdlog::level::err, LogLimiter::kNoUser, "lcm_error",
                   "event=lcm_error lcm_url={}", config.lcm_url);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

Result<void> Daemon::Run(const std::atomic<bool>* stop_flag) {
  Impl& d = *impl_;
  LogOomScoreAdj();
  // GL must work before anyone is served: each session makes its own context later.
  std::string device;
  std::vector<std::string> gpu_names;
  std::string gpu_cost;
  {
    int gpu = d.config.gpu;
    if (!d.config.gpu_id.empty()) {
      auto named = EglDeviceNamed(d.config.gpu_id);
      if (!named) return named.error();
      gpu = *named;
    }
    auto context = GlContext::Create(d.config.gl_platform, gpu);
    if (!context) return context.error();
    std::lock_guard lock(d.renderer_mutex);
    d.renderer = (*context)->renderer();
    device = (*context)->platform_description();
    gpu_names = ServedGpuNames(d.config, (*context)->drm_device_file());
    // auto's GPU cost model, once for every session to come (kept between starts).
    gpu_cost = PrepareGpuCost(d.config.gpu_cost_cache, d.renderer, (*context)->version());
    if (d.config.gpu_batch) d.StartBatcher(gpu);
  }
  d.status = std::make_unique<StatusSources>(StatusSources{d.config, d.stats, d.sessions, d.budget,
                                                           d.renderer, device, gpu_names, d.created,
                                                           d.compute_batcher.get()});
  // The metrics file's first write and the port come before the daemon is ready: a file that
  // cannot be written or a port taken is a start-up error, not a silent gap in the metrics.
  auto metrics = MetricsExport::Start(d.config, *d.status);
  if (!metrics) return metrics.error();
  SocketServer server(std::move(d.listener), d.config, d.sessions, d.stats, *d.workers, *d.status);
  // Both lines come before the socket answers: whoever finds the daemon ready finds them logged.
  spdlog::info(
      "event=daemon_ready name={} socket={} gl_renderer=\"{}\" gl_device=\"{}\" "
      "gpu_names=\"{}\" lcm_url={} max_sessions={} cpu_cores={} threads_per_session={} "
      "gpu_batch={} gpu_cost={}",
      d.config.name, SocketPathOf(d.config), d.renderer, device, fmt::join(gpu_names, ","),
      d.config.lcm_url, d.config.max_sessions, CpuCoresOf(d.config),
      CpuPoolThreads(d.config.exact_threads, CpuCoresOf(d.config)), d.compute_batcher != nullptr,
      gpu_cost);
  if (protocol::IsInProcessUrl(d.config.lcm_url)) {
    spdlog::warn(
        "event=lcm_in_process lcm_url={} message=\"no client can reach the session channels "
        "of an in-process LCM URL: clients connect and get an error; use udpm:// to serve "
        "them\"",
        d.config.lcm_url);
  }
  std::atomic<bool> stop_socket{false};
  std::thread socket_thread([&] { server.Run(stop_socket); });
  d.ServeMessages(stop_flag);
  // The socket thread stops first, so that no session opens while every session closes: one
  // opened then would get a worker after the registry had reaped the rest. The connections
  // close with `server`, after their clients have been told.
  stop_socket = true;
  socket_thread.join();
  spdlog::info("event=daemon_stopping sessions={}", d.sessions.size());
  d.CloseEverySession();
  // Every session closed: the last metrics file says so (sessions 0, far_up 0).
  (*metrics)->Stop();
  ClientLogLimiter().Flush(LogLimiter::Clock::now(), /*all=*/true);
  spdlog::info("event=daemon_stopped steps_total={}", d.stats.steps_total());
  return {};
}

void Daemon::Stop() { impl_->stop = true; }

std::string Daemon::gl_renderer() const {
  std::lock_guard lock(impl_->renderer_mutex);
  return impl_->renderer;
}

}  // namespace far::server
