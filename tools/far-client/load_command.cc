// far-client load: N concurrent clients, each with its own session and scene; throughput,
// latency percentiles and fairness per client and overall.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <thread>
#include <utility>

#include "cli_common.h"
#include "commands.h"
#include "cpu_burn.h"
#include "step_flags.h"
#include <nlohmann/json.hpp>

#include "far/base/quantile.h"
#include "far/io/scene_io.h"
#include "far/scenes/scenes.h"

namespace far::cli {
namespace {

using nlohmann::json;

// Per-client results of a load run.
struct LoadStats {
  std::vector<double> latency_ms;
  std::map<std::string, int> steps_by_method;  // the configuration that answered (auto varies)
  std::string last_reason;                     // auto's reason for its client's last step
  int errors = 0;
  std::string first_error;
  double cpu_burned_ms = 0;  // --client-cpu-ms, all steps together
};

// The load command's own flags.
struct LoadFlags {
  int clients = 4, steps = 100;  // steps 0: no limit (with --seconds)
  double seconds = 0;
  double client_cpu_ms = 0;  // CPU time each client burns before each step
  std::string scene;
  bool as_json = false;
  StepFlags step;
};

// What every client of a run shares: the flags, the request, the scene (empty: each makes a
// random soup), and the start line.
struct LoadRun {
  const client::ClientOptions& base;
  const LoadFlags& flags;
  const StepRequest& request;
  far::Scene scene;
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  Clock::time_point start;  // written before `go`, read after it

  Clock::time_point Deadline() const {
    return flags.seconds > 0 ? start + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(flags.seconds))
                             : Clock::time_point::max();
  }
};

// One client of the run (thread `i`): its own session and scene, then steps until the step
// count or the time is up.
void RunOneClient(LoadRun& run, int i, LoadStats& mine) {
  client::ClientOptions options = run.base;
  options.client_name = "load-" + std::to_string(i);
  auto client = client::Client::Connect(options);
  auto fail = [&](const far::Error& e) {
    if (mine.errors++ == 0) mine.first_error = far::ToString(e);
  };
  if (!client) {
    fail(client.error());
    run.ready++;
    return;
  }
  // Each client simulates its own scene: the given one, or a random soup of rigid objects.
  std::vector<far::SceneObject> objects =
      run.flags.scene.empty() ? far::scenes::RandomSoup(static_cast<uint64_t>(i), 24, 40, 3.0, 0.4)
                              : run.scene.objects;
  for (const auto& o : objects) {
    if (auto ok = (*client)->AddObject(o.id, o.mesh, o.motion, o.X_WO); !ok) fail(ok.error());
  }
  run.ready++;
  // Everyone starts together, once the main thread has set `start` and said go.
  while (!run.go) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const auto deadline = run.Deadline();
  const int steps = run.flags.steps;
  // After an error the client backs off (doubling, up to a second) instead of spinning;
  // a session the daemon ended is the end of this client.
  auto backoff = std::chrono::milliseconds(0);
  for (int s = 0; (steps <= 0 || s < steps) && Clock::now() < deadline; ++s) {
    if (backoff.count() > 0) std::this_thread::sleep_for(backoff);
    // The simulator's own work (--client-cpu-ms), on cores the daemon may share.
    mine.cpu_burned_ms += BurnThreadCpuMs(run.flags.client_cpu_ms);
    // Rigid objects drift a little every step, as a simulation would move them.
    bool posed = true;
    for (auto& o : objects) {
      if (o.motion != far::Motion::kRigid) continue;
      o.X_WO.translation.x() += 0.002 * std::sin(0.1 * s + o.id);
      if (auto ok = (*client)->SetPose(o.id, o.X_WO); !ok) {
        fail(ok.error());
        posed = false;
        break;
      }
    }
    const auto t0 = Clock::now();
    auto result =
        posed ? (*client)->Step(run.request)
              : far::Result<far::StepResult>(far::MakeError(far::ErrorCode::kBusy, "not posed"));
    if (!result) {
      if (posed) fail(result.error());
      if (result.error().code == far::ErrorCode::kUnavailable) break;
      backoff =
          std::clamp(backoff * 2, std::chrono::milliseconds(10), std::chrono::milliseconds(1000));
      continue;
    }
    backoff = std::chrono::milliseconds(0);
    ++mine.steps_by_method[result->stats.method];
    mine.last_reason = std::move(result->stats.method_reason);
    mine.latency_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
}

// The run's report: per client and overall, and the total number of errors.
struct LoadReport {
  json per_client = json::array();
  json overall;
  std::vector<double> all;  // every step's latency
  std::map<std::string, int> steps_by_method;
  int errors = 0;
  double fairness = 0;
};

LoadReport Summarize(const std::vector<LoadStats>& stats, double elapsed, double client_cpu_ms) {
  LoadReport report;
  double cpu_burned_ms = 0;
  size_t min_steps = SIZE_MAX, max_steps = 0;
  for (size_t i = 0; i < stats.size(); ++i) {
    const LoadStats& s = stats[i];
    report.all.insert(report.all.end(), s.latency_ms.begin(), s.latency_ms.end());
    report.errors += s.errors;
    cpu_burned_ms += s.cpu_burned_ms;
    for (const auto& [method, steps] : s.steps_by_method) report.steps_by_method[method] += steps;
    min_steps = std::min(min_steps, s.latency_ms.size());
    max_steps = std::max(max_steps, s.latency_ms.size());
    report.per_client.push_back({{"client", i},
                                 {"steps", s.latency_ms.size()},
                                 {"steps_per_s", s.latency_ms.size() / elapsed},
                                 {"p50_ms", Quantile(s.latency_ms, 0.5)},
                                 {"p90_ms", Quantile(s.latency_ms, 0.9)},
                                 {"p99_ms", Quantile(s.latency_ms, 0.99)},
                                 {"errors", s.errors},
                                 {"first_error", s.first_error},
                                 {"last_reason", s.last_reason},
                                 {"client_cpu_ms_total", s.cpu_burned_ms}});
  }
  const std::vector<double>& all = report.all;
  report.fairness =
      min_steps > 0 ? static_cast<double>(max_steps) / static_cast<double>(min_steps) : 0.0;
  report.overall = {{"clients", stats.size()},
                    {"seconds", elapsed},
                    {"steps", all.size()},
                    {"steps_per_s", all.size() / elapsed},
                    {"p50_ms", Quantile(all, 0.5)},
                    {"p90_ms", Quantile(all, 0.9)},
                    {"p99_ms", Quantile(all, 0.99)},
                    {"max_ms", Quantile(all, 1.0)},
                    {"errors", report.errors},
                    {"fairness_max_over_min_steps", report.fairness},
                    {"steps_by_method", report.steps_by_method},
                    {"client_cpu_ms_per_step", client_cpu_ms},
                    {"client_cpu_ms_total", cpu_burned_ms}};
  return report;
}

// auto's choice at each client's last step, the clients that share one named together ("auto:
// gpu is the fastest measured" for 14 clients), with one client's whole reason for each.
void PrintLastReasons(const LoadReport& report) {
  std::map<std::string, std::vector<int>> clients_by_choice;
  for (const auto& c : report.per_client) {
    const std::string reason = c["last_reason"].get<std::string>();
    if (reason.empty()) continue;
    clients_by_choice[reason.substr(0, reason.find(" ("))].push_back(c["client"].get<int>());
  }
  for (const auto& [choice, clients] : clients_by_choice) {
    const std::string& whole =
        report.per_client[static_cast<size_t>(clients.front())]["last_reason"]
            .get_ref<const std::string&>();
    std::printf("last step's reason, %zu client(s): %s\n  client %d: %s\n", clients.size(),
                choice.c_str(), clients.front(), whole.c_str());
  }
}

void PrintTable(const LoadReport& report, double elapsed) {
  std::printf("%-8s %8s %10s %9s %9s %9s %7s\n", "client", "steps", "steps/s", "p50 ms", "p90 ms",
              "p99 ms", "errors");
  for (const auto& c : report.per_client) {
    std::printf("%-8d %8zu %10.1f %9.3f %9.3f %9.3f %7d\n", c["client"].get<int>(),
                c["steps"].get<size_t>(), c["steps_per_s"].get<double>(), c["p50_ms"].get<double>(),
                c["p90_ms"].get<double>(), c["p99_ms"].get<double>(), c["errors"].get<int>());
    if (!c["first_error"].get<std::string>().empty()) {
      std::printf("         first error: %s\n", c["first_error"].get<std::string>().c_str());
    }
  }
  const std::vector<double>& all = report.all;
  std::printf(
      "overall: %zu steps in %.2f s = %.1f steps/s; latency p50 %.3f p90 %.3f p99 %.3f max %.3f "
      "ms; "
      "errors %d; fairness (max/min steps per client) %.2f\n",
      all.size(), elapsed, all.size() / elapsed, Quantile(all, 0.5), Quantile(all, 0.9),
      Quantile(all, 0.99), Quantile(all, 1.0), report.errors, report.fairness);
  std::string methods;
  for (const auto& [method, steps] : report.steps_by_method) {
    methods += (methods.empty() ? "" : ", ") + method + " " + std::to_string(steps);
  }
  std::printf("steps by method: %s\n", methods.empty() ? "none answered" : methods.c_str());
  PrintLastReasons(report);
  if (const double per_step = report.overall["client_cpu_ms_per_step"].get<double>();
      per_step > 0) {
    std::printf("client CPU burned: %.1f ms per step before its request, %.1f ms in all\n",
                per_step, report.overall["client_cpu_ms_total"].get<double>());
  }
}

int RunLoad(const client::ClientOptions& base, const LoadFlags& flags, const StepRequest& request) {
  LoadRun run{base, flags, request, {}, {}, {}, {}};
  if (!flags.scene.empty()) {
    auto loaded = far::ReadScene(flags.scene);
    if (!loaded) return Fail(loaded.error());
    run.scene = std::move(*loaded);
  }
  std::vector<LoadStats> stats(static_cast<size_t>(flags.clients));
  std::vector<std::thread> threads;
  for (int i = 0; i < flags.clients; ++i) {
    threads.emplace_back(
        [&run, &stats, i] { RunOneClient(run, i, stats[static_cast<size_t>(i)]); });
  }
  while (run.ready < flags.clients) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  run.start = Clock::now();
  run.go = true;  // (release: the workers read `start` after seeing it)
  for (auto& t : threads) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - run.start).count();

  const LoadReport report = Summarize(stats, elapsed, flags.client_cpu_ms);
  if (flags.as_json) {
    std::cout << json{{"overall", report.overall}, {"per_client", report.per_client}}.dump(2)
              << "\n";
  } else {
    PrintTable(report, elapsed);
  }
  return report.errors == 0 ? 0 : 1;
}

}  // namespace

Command AddLoadCommand(CLI::App& app, const GlobalFlags& global) {
  auto flags = std::make_shared<LoadFlags>();
  Command command;
  command.app =
      app.add_subcommand("load",
                         "Run N concurrent clients, each with its own session and scene; "
                         "prints throughput and latency percentiles per client and overall");
  CLI::App* load = command.app;
  load->add_option("--clients", flags->clients, "concurrent clients (threads), 1..1024")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  CLI::Option* steps =
      load->add_option("--steps", flags->steps,
                       "steps per client (default: 100, or no limit when --seconds is given; "
                       "0: no limit, needs --seconds)")
          ->check(CLI::NonNegativeNumber);
  CLI::Option* seconds =
      load->add_option("--seconds", flags->seconds,
                       "stop after this many seconds (alone: run until then, however many steps)")
          ->check(CLI::PositiveNumber);
  load->add_option("--scene", flags->scene,
                   "scene each client uploads (default: a random soup per client)");
  load->add_option("--client-cpu-ms", flags->client_cpu_ms,
                   "CPU ms each client burns on its own thread before each step, as a "
                   "simulator's physics step would (0..10000; default 0: none)")
      ->check([](const std::string& text) -> std::string {
        // CLI::Range lets NaN through: every comparison with it is false.
        char* end = nullptr;
        const double ms = std::strtod(text.c_str(), &end);
        if (!text.empty() && *end == '\0' && std::isfinite(ms) && ms >= 0 && ms <= kMaxClientCpuMs)
          return "";
        return "'" + text + "' is not a number of milliseconds in [0, 10000]";
      });
  load->add_flag("--json", flags->as_json, "print JSON");
  flags->step.Add(load);
  flags->step.AddTimeout(load);
  command.run = [&global, flags, steps, seconds] {
    auto request = flags->step.Request();
    if (!request) return Fail(request.error());
    // --seconds alone means "for this long": the step count's default must not cut it short.
    if (seconds->count() > 0 && steps->count() == 0) flags->steps = 0;
    if (flags->steps <= 0 && seconds->count() == 0) {
      return Fail(MakeError(ErrorCode::kInvalidArgument,
                            "--steps 0 (no limit) needs --seconds: the run would never end"));
    }
    auto base = global.Options();
    if (!base) return Fail(base.error());
    auto options = flags->step.Options(*base);
    if (!options) return Fail(options.error());
    return RunLoad(*options, *flags, *request);
  };
  return command;
}

}  // namespace far::cli
