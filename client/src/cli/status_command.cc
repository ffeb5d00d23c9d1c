// far-client ping and status: is a daemon there, and what is it doing.
#include <iostream>

#include "cli_common.h"
#include <nlohmann/json.hpp>

namespace far::cli {
namespace {

using nlohmann::json;

int PrintStatus(const std::string& url, std::chrono::milliseconds timeout, bool as_json) {
  auto status = client::Client::Status(url, timeout);
  if (!status) return Fail(status.error());
  if (as_json) {
    json sessions = json::array();
    for (const auto& s : status->sessions) {
      sessions.push_back({{"id", s.id},
                          {"client", s.client_name},
                          {"steps", s.steps},
                          {"objects", s.objects},
                          {"latency_p50_ms", s.latency_p50_ms},
                          {"latency_p99_ms", s.latency_p99_ms}});
    }
    json errors = json::object();
    for (const auto& [kind, count] : status->errors_by_kind) errors[kind] = count;
    std::cout << json{{"daemon_version", status->daemon_version},
                      {"gl_renderer", status->gl_renderer},
                      {"uptime_ms", status->uptime_ms},
                      {"steps_total", status->steps_total},
                      {"errors_total", status->errors_total},
                      {"errors_by_kind", errors},
                      {"rejected_messages_total", status->rejected_messages_total},
                      {"max_sessions", status->max_sessions},
                      {"latency_ms",
                       {{"p50", status->latency_p50_ms},
                        {"p90", status->latency_p90_ms},
                        {"p99", status->latency_p99_ms},
                        {"max", status->latency_max_ms},
                        {"samples", status->latency_samples}}},
                      {"sessions", sessions}}
                     .dump(2)
              << "\n";
    return 0;
  }
  std::printf("far-daemon %s, up %.1f s\nGL_RENDERER: %s\n", status->daemon_version.c_str(),
              status->uptime_ms / 1000.0, status->gl_renderer.c_str());
  std::printf("steps: %lld  errors: %lld  rejected messages: %lld\n",
              static_cast<long long>(status->steps_total),
              static_cast<long long>(status->errors_total),
              static_cast<long long>(status->rejected_messages_total));
  std::printf("step latency ms: p50 %.3f  p90 %.3f  p99 %.3f  max %.3f  (%lld steps)\n",
              status->latency_p50_ms, status->latency_p90_ms, status->latency_p99_ms,
              status->latency_max_ms, static_cast<long long>(status->latency_samples));
  for (const auto& [kind, count] : status->errors_by_kind) {
    std::printf("errors %-20s %lld\n", kind.c_str(), static_cast<long long>(count));
  }
  std::printf("sessions: %zu of %d\n", status->sessions.size(), status->max_sessions);
  for (const auto& s : status->sessions) {
    std::printf("  session %lld  %-16s steps %-8lld objects %-6d p50 %.3f ms  p99 %.3f ms\n",
                static_cast<long long>(s.id), s.client_name.c_str(),
                static_cast<long long>(s.steps), s.objects, s.latency_p50_ms, s.latency_p99_ms);
  }
  return 0;
}

}  // namespace

Command AddPingCommand(CLI::App& app, const GlobalFlags& global) {
  Command command;
  command.app =
      app.add_subcommand("ping", "Check that a daemon answers; prints the round-trip time");
  command.run = [&global] {
    const client::ClientOptions options = global.Options();
    const auto t0 = Clock::now();
    auto answered = client::Client::Status(options.lcm_url, options.timeout);
    if (!answered) return Fail(answered.error());
    std::printf("far-daemon answered on %s in %.3f ms (GL_RENDERER: %s)\n", options.lcm_url.c_str(),
                MsSince(t0), answered->gl_renderer.c_str());
    return 0;
  };
  return command;
}

Command AddStatusCommand(CLI::App& app, const GlobalFlags& global) {
  auto as_json = std::make_shared<bool>(false);
  Command command;
  command.app = app.add_subcommand("status",
                                   "Print the daemon's status: GL renderer, sessions, steps, "
                                   "latency percentiles, errors by kind");
  command.app->add_flag("--json", *as_json, "print JSON");
  command.run = [&global, as_json] {
    const client::ClientOptions options = global.Options();
    return PrintStatus(options.lcm_url, options.timeout, *as_json);
  };
  return command;
}

}  // namespace far::cli
