// far-client ping and status: is a daemon there, and what is it doing.
#include <unistd.h>

#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include <nlohmann/json.hpp>

#include "far/client/discovery.h"

namespace far::cli {
namespace {

using nlohmann::json;

json StatusJson(const client::DaemonStatus& status) {
  json sessions = json::array();
  for (const auto& s : status.sessions) {
    sessions.push_back({{"id", s.id},
                        {"uid", s.uid},
                        {"pid", s.pid},
                        {"client", s.client_name},
                        {"steps", s.steps},
                        {"objects", s.objects},
                        {"triangles", s.triangles},
                        {"latency_p50_ms", s.latency_p50_ms},
                        {"latency_p99_ms", s.latency_p99_ms}});
  }
  json errors = json::object();
  for (const auto& [kind, count] : status.errors_by_kind) errors[kind] = count;
  json methods = json::object();
  for (const auto& [method, steps] : status.steps_by_method) methods[method] = steps;
  return {{"daemon_version", status.daemon_version},
          {"daemon_name", status.daemon_name},
          {"socket", status.socket_path},
          {"gl_renderer", status.gl_renderer},
          {"gl_device", status.gl_device},
          {"lcm_url", status.lcm_url},
          {"channel_prefix", status.channel_prefix},
          {"uptime_ms", status.uptime_ms},
          {"steps_total", status.steps_total},
          {"errors_total", status.errors_total},
          {"errors_by_kind", errors},
          {"rejected_messages_total", status.rejected_messages_total},
          {"max_sessions", status.max_sessions},
          {"max_sessions_per_user", status.max_sessions_per_user},
          {"sessions_open", status.sessions_open},
          {"latency_ms",
           {{"p50", status.latency_p50_ms},
            {"p90", status.latency_p90_ms},
            {"p99", status.latency_p99_ms},
            {"max", status.latency_max_ms},
            {"samples", status.latency_samples}}},
          {"sessions", sessions},
          {"daemon_pid", status.daemon_pid},
          {"gpu_names", status.gpu_names},
          {"opens_refused_total", status.opens_refused_total},
          {"memory_rss_bytes", status.memory_rss_bytes},
          {"segment_bytes", status.segment_bytes},
          {"steps_by_method", methods}};
}

std::string Joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ",") + name;
  return text.empty() ? "-" : text;
}

// far-client status --all: every daemon on this machine, one line each.
int PrintAll(const client::ClientOptions& options, bool as_json) {
  const std::vector<client::FoundDaemon> found = client::FindDaemons(options);
  if (as_json) {
    json all = json::array();
    for (const auto& daemon : found) {
      all.push_back(daemon.status ? StatusJson(*daemon.status)
                                  : json{{"socket", daemon.socket_path}, {"error", daemon.error}});
    }
    std::cout << all.dump(2) << "\n";
    return 0;
  }
  if (found.empty()) std::printf("no far-daemon sockets on this machine\n");
  std::printf("%-12s %-8s %-9s %-9s %-10s %-10s %-18s %s\n", "name", "pid", "sessions", "steps",
              "p50 ms", "p99 ms", "gpu names", "socket / renderer");
  for (const auto& daemon : found) {
    if (!daemon.status) {
      std::printf("%-12s %-8s %-9s %-9s %-10s %-10s %-18s %s (%s)\n", "?", "-", "-", "-", "-", "-",
                  "-", daemon.socket_path.c_str(), daemon.error.c_str());
      continue;
    }
    const client::DaemonStatus& s = *daemon.status;
    const std::string sessions =
        std::to_string(s.sessions_open) + "/" + std::to_string(s.max_sessions);
    std::printf("%-12s %-8d %-9s %-9lld %-10.3f %-10.3f %-18s %s (%s)\n", s.daemon_name.c_str(),
                s.daemon_pid, sessions.c_str(), static_cast<long long>(s.steps_total),
                s.latency_p50_ms, s.latency_p99_ms, Joined(s.gpu_names).c_str(),
                daemon.socket_path.c_str(), s.gl_renderer.c_str());
  }
  return 0;
}

void PrintText(const client::DaemonStatus& status) {
  std::printf("far-daemon %s '%s', up %.1f s, socket %s\n", status.daemon_version.c_str(),
              status.daemon_name.c_str(), status.uptime_ms / 1000.0, status.socket_path.c_str());
  std::printf("GL_RENDERER: %s (%s); GPU names: %s\n", status.gl_renderer.c_str(),
              status.gl_device.c_str(), Joined(status.gpu_names).c_str());
  std::printf("pid %d, resident memory %.1f MiB, session segments %.1f MiB\n", status.daemon_pid,
              status.memory_rss_bytes / 1048576.0, status.segment_bytes / 1048576.0);
  std::printf("LCM: %s, channels %sS<id>_REQ/_REPLY\n", status.lcm_url.c_str(),
              status.channel_prefix.c_str());
  std::printf("steps: %lld  errors: %lld  rejected messages: %lld\n",
              static_cast<long long>(status.steps_total),
              static_cast<long long>(status.errors_total),
              static_cast<long long>(status.rejected_messages_total));
  std::printf("step latency ms: p50 %.3f  p90 %.3f  p99 %.3f  max %.3f  (%lld steps)\n",
              status.latency_p50_ms, status.latency_p90_ms, status.latency_p99_ms,
              status.latency_max_ms, static_cast<long long>(status.latency_samples));
  for (const auto& [method, steps] : status.steps_by_method) {
    std::printf("steps by %-18s %lld\n", method.c_str(), static_cast<long long>(steps));
  }
  for (const auto& [kind, count] : status.errors_by_kind) {
    std::printf("errors %-20s %lld\n", kind.c_str(), static_cast<long long>(count));
  }
  std::printf("session opens refused: %lld\n", static_cast<long long>(status.opens_refused_total));
  // The daemon lists the asking user's sessions, and every session to root.
  const char* whose = getuid() == 0 ? "every user's" : "yours";
  std::printf("sessions: %d open of %d (at most %d per user); %s:%s\n", status.sessions_open,
              status.max_sessions, status.max_sessions_per_user, whose,
              status.sessions.empty() ? " none" : "");
  for (const auto& s : status.sessions) {
    std::printf(
        "  session %lld  uid %d  %-16s steps %-8lld objects %-6d triangles %-9lld p50 %.3f ms  "
        "p99 %.3f ms\n",
        static_cast<long long>(s.id), s.uid, s.client_name.c_str(), static_cast<long long>(s.steps),
        s.objects, static_cast<long long>(s.triangles), s.latency_p50_ms, s.latency_p99_ms);
  }
}

}  // namespace

Command AddPingCommand(CLI::App& app, const GlobalFlags& global) {
  Command command;
  command.app =
      app.add_subcommand("ping", "Check that a daemon answers; prints the round-trip time");
  command.run = [&global] {
    auto options = global.Options();
    if (!options) return Fail(options.error());
    const auto t0 = Clock::now();
    auto answered = client::Client::Status(*options);
    if (!answered) return Fail(answered.error());
    std::printf("far-daemon '%s' answered on %s in %.3f ms (GL_RENDERER: %s)\n",
                answered->daemon_name.c_str(), answered->socket_path.c_str(), MsSince(t0),
                answered->gl_renderer.c_str());
    return 0;
  };
  return command;
}

Command AddStatusCommand(CLI::App& app, const GlobalFlags& global) {
  auto as_json = std::make_shared<bool>(false);
  Command command;
  command.app = app.add_subcommand("status",
                                   "Print the daemon's status: GL renderer and device, sessions "
                                   "(your own; all for root), steps, latency percentiles, "
                                   "errors by kind");
  auto all = std::make_shared<bool>(false);
  command.app->add_flag("--json", *as_json, "print JSON");
  command.app->add_flag("--all", *all,
                        "every daemon on this machine (each socket in the socket directories), "
                        "one line each; with --json an array");
  command.run = [&global, as_json, all] {
    auto options = global.Options();
    if (!options) return Fail(options.error());
    if (*all) return PrintAll(*options, *as_json);
    auto status = client::Client::Status(*options);
    if (!status) return Fail(status.error());
    if (*as_json) {
      std::cout << StatusJson(*status).dump(2) << "\n";
    } else {
      PrintText(*status);
    }
    return 0;
  };
  return command;
}

}  // namespace far::cli
