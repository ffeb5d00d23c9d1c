#include "daemon.h"

#include <chrono>
#include <future>
#include <mutex>
#include <thread>

#include "daemon_stats.h"
#include "message_handlers.h"
#include "replier.h"
#include "session_registry.h"
#include "step_runner.h"
#include <spdlog/spdlog.h>

#include "far/protocol/lcm_bus.h"
#include "far/protocol/shm_segment.h"

namespace far::server {

struct Daemon::Impl {
  DaemonConfig config;
  std::unique_ptr<protocol::LcmBus> bus;
  DaemonStats stats;
  SessionRegistry sessions{config};
  std::unique_ptr<Replier> replier;
  std::unique_ptr<MessageHandlers> handlers;
  std::unique_ptr<StepRunner> runner;
  std::atomic<bool> stop{false};
  mutable std::mutex renderer_mutex;
  std::string renderer;

  explicit Impl(const DaemonConfig& c) : config(c) {}
  bool Stopping(const std::atomic<bool>* stop_flag) const {
    return stop || (stop_flag != nullptr && stop_flag->load());
  }
  void ServeMessages(const std::atomic<bool>* stop_flag);
};

Daemon::Daemon(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Daemon::~Daemon() = default;

Result<std::unique_ptr<Daemon>> Daemon::Create(const DaemonConfig& config, DaemonTestHooks hooks) {
  if (auto ok = ValidateDaemonConfig(config); !ok) return ok.error();
  auto impl = std::make_unique<Impl>(config);
  auto bus = protocol::LcmBus::Create(config.lcm_url);
  if (!bus) return bus.error();
  impl->bus = std::move(*bus);
  const int stale = protocol::RemoveStaleSegments();
  if (stale > 0) spdlog::info("event=stale_segments_removed count={}", stale);
  impl->replier = std::make_unique<Replier>(*impl->bus, impl->stats);
  impl->handlers =
      std::make_unique<MessageHandlers>(impl->config, impl->sessions, *impl->replier, impl->stats);
  impl->runner = std::make_unique<StepRunner>(impl->config, impl->sessions, *impl->handlers,
                                              *impl->replier, impl->stats);
  impl->handlers->Subscribe(*impl->bus, std::move(hooks.before_message));
  return std::unique_ptr<Daemon>(new Daemon(std::move(impl)));
}

// The LCM thread: handles messages and reaps silent sessions until stopped.
void Daemon::Impl::ServeMessages(const std::atomic<bool>* stop_flag) {
  auto last_reap = std::chrono::steady_clock::now();
  while (!Stopping(stop_flag)) {
    const bool handled = bus->Handle(std::chrono::milliseconds(100));
    // (a signal that stops the daemon also interrupts LCM's wait: not an error)
    if (!handled && !Stopping(stop_flag)) {
      spdlog::error("event=lcm_error lcm_url={}", config.lcm_url);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (std::chrono::steady_clock::now() - last_reap > std::chrono::milliseconds(250)) {
      handlers->ReapSilentSessions();
      last_reap = std::chrono::steady_clock::now();
    }
  }
}

Result<void> Daemon::Run(const std::atomic<bool>* stop_flag) {
  Impl& d = *impl_;
  std::promise<Result<std::string>> ready;
  auto renderer = ready.get_future();
  std::thread gl([&d, p = std::move(ready)]() mutable { d.runner->Run(std::move(p)); });
  auto made = renderer.get();
  if (!made) {
    gl.join();
    return made.error();
  }
  {
    std::lock_guard lock(d.renderer_mutex);
    d.renderer = *made;
  }
  d.handlers->set_renderer(*made);
  spdlog::info("event=daemon_ready gl_renderer=\"{}\" lcm_url={} max_sessions={}", *made,
               d.config.lcm_url, d.config.max_sessions);
  d.ServeMessages(stop_flag);
  // Drain: no new steps; the GL thread finishes the queued ones, then frees every session.
  spdlog::info("event=daemon_stopping queued_steps={}", d.sessions.queued());
  d.sessions.Stop();
  gl.join();
  spdlog::info("event=daemon_stopped steps_total={}", d.stats.steps_total());
  return {};
}

void Daemon::Stop() { impl_->stop = true; }

std::string Daemon::gl_renderer() const {
  std::lock_guard lock(impl_->renderer_mutex);
  return impl_->renderer;
}

}  // namespace far::server
