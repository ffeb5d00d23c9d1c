// Issue 10's hardening, measured against a real far-daemon (started here, one per part, with
// its default limits) and printed as markdown tables for bench/RESULTS.md:
//   (a) a healthy client's step latency while another client steps the largest legal scene
//       with the brute-force exact method (each of its steps runs until the step deadline),
//       in alternating unloaded and loaded phases;
//   (b) the same healthy client while this process floods LCM with garbage and forged step
//       requests; the daemon's rejected-message counter and log growth;
//   (c) one user opening sessions as fast as it can, and a second user's opens meanwhile;
//   (d) the daemon's resident size before, with and after 4 sessions of the largest scene;
//   (e) one uid (1001) holding 4 idle sessions of 2M degenerate triangles, and what root's
//       sessions then get (issue 41);
//   (f) four uids (1001-1004) holding 16 sessions each, and root's opens meanwhile (issue 41);
//   (g) what a lost datagram costs a light client on its default timeout (its step request or
//       reply lost on purpose; a forged-request flood; issue 41), lost_datagrams.h.
// And issue 41's memory attacks (memory_attacks.h; not in the default --parts):
//   (h) sessions opened and closed with their segments' descriptors kept (hoarding);
//   (i) a client killed while its step runs; (j) a flood of 60 KB datagrams.
// And issue 41's log floods and descriptor exhaustion (not in the default --parts):
//   (l) what a client's floods add to the daemon's log (a step flood, an open flood);
//   (n) the daemon's CPU while it is out of file descriptors (RLIMIT_NOFILE), and
//       its recovery.
// Run inside a network namespace (it re-runs itself through deploy/netns-run.sh otherwise):
//   deploy/netns-run.sh build/release/bench/daemon/far_hardening_study [--seconds 6]
#include <sys/resource.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <future>
#include <thread>

#include "fair_shares.h"
#include "garbage_flood.h"
#include "healthy_client.h"
#include "large_scene.h"
#include "log_flood.h"
#include "lost_datagrams.h"
#include "memory_attacks.h"
#include "slot_exhaustion.h"
#include "study_daemon.h"
#include <CLI/CLI.hpp>

#include "far/base/quantile.h"
#include "far/protocol/local_socket.h"

namespace far::study {
namespace {

using namespace std::chrono_literals;

struct Settings {
  double seconds = 5;             // one phase of (a) and (b)
  int rounds = 4;                 // unloaded + loaded phase pairs of (a) and (b)
  int64_t triangles = 1'990'000;  // the heavy scene (the default max_triangles_per_session: 2M)
  double flood_rate = 50'000;
  int hog_attempts = 100;
  std::string parts = "abcd";
  int hoard_sessions = 40;            // (h)
  KilledClientSetup killed;           // (i)
  int64_t flood_bytes = 60'000;       // (j): bytes per datagram
  double log_flood_seconds = 20;      // each flood of (l)
  std::string heavy_method = "aabb";  // the heaviest legal: exact refuses over 2^30 pairs
  // Contacts among the triangles within this distance of a partner object's box: a wider
  // search, so that each heavy step runs until its deadline (0: plain contacts).
  double heavy_distance = 2;
  std::string daemon = FAR_DAEMON_PATH;
  std::vector<std::string> daemon_args;  // added to every far-daemon's command line
  // The healthy client's steps per second in (a) and (b) (0: back to back, as fast as it can).
  // 500: a simulator's control rate, under the daemon's per-session request limit (2000/s),
  // which a back-to-back client reaches on a quiet machine (it is then refused as "busy": no
  // longer a healthy client by the daemon's own rules).
  double healthy_rate = 500;
  int loss_trials = 3;  // steps per loss case of (g)
};

// How the healthy client steps, for the tables' captions.
std::string HealthyPace(const Settings& settings) {
  if (settings.healthy_rate <= 0) return "steps back to back";
  char text[96];
  std::snprintf(text, sizeof(text), "one step every %.2f ms (%.0f steps/s, a simulator's clock)",
                1000 / settings.healthy_rate, settings.healthy_rate);
  return text;
}

std::unique_ptr<StudyDaemon> StartDaemon(const Settings& settings,
                                         const std::vector<std::string>& args = {}) {
  std::vector<std::string> all = args;
  all.insert(all.end(), settings.daemon_args.begin(), settings.daemon_args.end());
  auto daemon = StudyDaemon::Start(settings.daemon, all);
  if (!daemon) {
    std::fprintf(stderr, "far_hardening_study: %s\n", far::ToString(daemon.error()).c_str());
    std::exit(1);
  }
  return std::move(*daemon);
}

[[noreturn]] void Die(const std::string& what, const Error& error) {
  std::fprintf(stderr, "far_hardening_study: %s: %s\n", what.c_str(), far::ToString(error).c_str());
  std::exit(1);
}

void PrintHeader(int argc, char** argv, const Settings& settings) {
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M", std::localtime(&now));
  auto daemon = StartDaemon(settings);
  auto status = daemon->Status();
  std::string command;
  for (int i = 0; i < argc; ++i) command += std::string(i ? " " : "") + argv[i];
  std::printf("# far-daemon hardening study\n\n");
  std::printf("- date: %s\n- machine: %u cores (%s), load average at start: ", date,
              std::thread::hardware_concurrency(), CpuModel().c_str());
  std::ifstream load("/proc/loadavg");
  std::string one, five;
  load >> one >> five;
  std::printf("%s (1 min), %s (5 min)\n", one.c_str(), five.c_str());
  std::printf("- GL_RENDERER: %s\n- command: `%s`\n",
              status ? status->gl_renderer.c_str() : "unknown", command.c_str());
  std::printf(
      "- every part starts its own far-daemon with its default limits, except where said\n\n");
}

double Q(const std::vector<double>& ms, double q) { return ms.empty() ? 0 : Quantile(ms, q); }

void PrintLatencyRow(const char* phase, int round, const LatencySample& s,
                     const std::string& extra) {
  std::printf("| %s | %d | %zu | %.1f | %.3f | %.3f | %.3f | %d | %s |\n", phase, round,
              s.ms.size(), s.StepsPerSecond(), Q(s.ms, 0.5), Q(s.ms, 0.99), Q(s.ms, 1.0), s.errors,
              extra.c_str());
}

// How the daemon's log says it demoted session `id` ("step_ms=... step=running nice=10"), or
// "" when it did not.
std::string Demotion(const StudyDaemon& daemon, int64_t id) {
  std::ifstream log(daemon.log_path());
  std::string line;
  const std::string tag = "event=session_demoted session=" + std::to_string(id) + " ";
  while (std::getline(log, line)) {
    if (const size_t at = line.find(tag); at != std::string::npos)
      return line.substr(at + tag.size());
  }
  return "";
}

void PrintSummary(const LatencySample& unloaded, const LatencySample& loaded,
                  std::vector<double> ratios) {
  std::printf(
      "\n| healthy client, all rounds | steps | steps/s | p50 ms | p99 ms | max ms | errors |\n");
  std::printf("| --- | --: | --: | --: | --: | --: | --: |\n");
  for (const auto& [name, s] : {std::pair{"unloaded", &unloaded}, {"loaded", &loaded}}) {
    std::printf("| %s | %zu | %.1f | %.3f | %.3f | %.3f | %d |\n", name, s->ms.size(),
                s->StepsPerSecond(), Q(s->ms, 0.5), Q(s->ms, 0.99), Q(s->ms, 1.0), s->errors);
  }
  // Each loaded phase against the unloaded phase just before it: what other load the machine
  // had then weighs on both alike (all rounds pooled mixes quiet and noisy phases).
  const double median = Q(ratios, 0.5);
  std::printf(
      "\nLoaded p99 / unloaded p99 per round (the loaded phase against the unloaded phase "
      "before it): median **%.2f**, from %.2f to %.2f (goal: at most 2): **%s**. All rounds "
      "pooled: %.2f. Steps/s loaded / unloaded: %.0f%%.\n",
      median, Q(ratios, 0), Q(ratios, 1), median <= 2 ? "met" : "not met",
      Q(loaded.ms, 0.99) / std::max(1e-9, Q(unloaded.ms, 0.99)),
      100 * loaded.StepsPerSecond() / std::max(1e-9, unloaded.StepsPerSecond()));
}

// The heavy client steps back to back until the phase is over (its last step may end later:
// the next phase waits for it). Says how its steps went.
std::string HeavySteps(client::Client& heavy, const StepRequest& request,
                       const std::atomic<bool>& phase_over) {
  int finished = 0, failed = 0;
  double longest_s = 0;
  std::string error;
  while (!phase_over) {
    const auto start = std::chrono::steady_clock::now();
    auto result = heavy.Step(request);
    longest_s = std::max(
        longest_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (result) {
      ++finished;
    } else {
      ++failed;
      error = far::ToString(result.error());
    }
  }
  char text[512];
  std::snprintf(text, sizeof(text), "%d finished, %d failed, longest %.1f s%s%s", finished, failed,
                longest_s, error.empty() ? "" : ": ", error.c_str());
  return text;
}

// (a) The heavy client's steps run until the step deadline, which is one phase long.
void StudyHeavyClient(const Settings& settings, const Scene& scene) {
  const int phase_ms = static_cast<int>(settings.seconds * 1000);
  auto daemon = StartDaemon(settings, {"--step-deadline-ms", std::to_string(phase_ms)});
  auto healthy = HealthyClient::Open(*daemon, "healthy", 5s);
  if (!healthy) Die("healthy client", healthy.error());
  auto heavy = client::Client::Connect(daemon->Options("heavy", 600s));
  if (!heavy) Die("heavy client", heavy.error());
  const auto upload_start = std::chrono::steady_clock::now();
  if (auto ok = UploadInParts(**heavy, scene); !ok) Die("heavy upload", ok.error());
  const double upload_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - upload_start).count();
  const std::string demoted_by_upload = Demotion(*daemon, (*heavy)->session_id());
  std::printf("## (a) A healthy client beside the heaviest legal client\n\n");
  std::printf(
      "Healthy: 8 rigid clusters of 128 triangles (1,024), all moved every step, method bvh, "
      "contacts, %s. Heavy: ScalingScene of %lld triangles, %lld vertices "
      "(uploaded in %.2f s), method %s, contacts, search distance %g (every triangle within "
      "that distance of a partner object's box is a candidate: more work, the same contacts), "
      "steps back to back; each runs until the step deadline (far-daemon --step-deadline-ms "
      "%d, one phase). Phases of %.0f s alternate, unloaded first; a loaded phase's last heavy "
      "step ends before the next phase starts.\n\n",
      HealthyPace(settings).c_str(), static_cast<long long>(TriangleCount(scene)),
      static_cast<long long>(VertexCount(scene)), upload_s, settings.heavy_method.c_str(),
      settings.heavy_distance, phase_ms, settings.seconds);
  std::printf(
      "| phase | round | steps | steps/s | p50 ms | p99 ms | max ms | errors | p99 / unloaded "
      "p99 | heavy client's steps |\n");
  std::printf("| --- | --: | --: | --: | --: | --: | --: | --: | --: | --- |\n");
  StepRequest heavy_request;
  heavy_request.method = *ParseMethod(settings.heavy_method);
  heavy_request.output = Output::kContacts;
  if (settings.heavy_distance > 0) heavy_request.distance = settings.heavy_distance;
  LatencySample unloaded, loaded;
  std::vector<double> ratios;
  for (int round = 1; round <= settings.rounds; ++round) {
    const LatencySample quiet = (*healthy)->StepFor(settings.seconds, settings.healthy_rate);
    PrintLatencyRow("unloaded", round, quiet, "- | -");
    unloaded.Merge(quiet);
    std::atomic<bool> phase_over{false};
    auto heavy_steps = std::async(std::launch::async,
                                  [&] { return HeavySteps(**heavy, heavy_request, phase_over); });
    const LatencySample busy = (*healthy)->StepFor(settings.seconds, settings.healthy_rate);
    phase_over = true;
    ratios.push_back(Q(busy.ms, 0.99) / std::max(1e-9, Q(quiet.ms, 0.99)));
    char ratio[32];
    std::snprintf(ratio, sizeof(ratio), "%.2f | ", ratios.back());
    PrintLatencyRow("loaded", round, busy, ratio + heavy_steps.get());
    loaded.Merge(busy);
  }
  PrintSummary(unloaded, loaded, ratios);
  const std::string demotion = Demotion(*daemon, (*heavy)->session_id());
  std::printf(
      "The daemon demoted the heavy session %s%s%s.\n\n",
      !demoted_by_upload.empty() ? "during its upload: " : "",
      demotion.empty() ? "never" : "(log: ", demotion.empty() ? "" : (demotion + ")").c_str());
}

int64_t Rejected(const StudyDaemon& daemon) {
  auto status = daemon.Status();
  return status ? status->rejected_messages_total : -1;
}

// One flood phase of (b): what the healthy client, the flood and the daemon did.
struct FloodRound {
  LatencySample busy;
  FloodReport sent;
  double daemon_cpu = 0;  // cores
  int64_t rejected = 0, log_growth = 0;
};

FloodRound FloodPhase(StudyDaemon& daemon, HealthyClient& healthy,
                      const client::DaemonStatus& status, const Settings& settings) {
  FloodRound round;
  const int64_t rejected_before = Rejected(daemon), log_before = daemon.LogBytes();
  const double cpu_before = daemon.CpuSeconds();
  auto flood = GarbageFlood::Start(status.lcm_url, status.channel_prefix, healthy.session_id(),
                                   settings.flood_rate);
  if (!flood) Die("flood", flood.error());
  round.busy = healthy.StepFor(settings.seconds, settings.healthy_rate);
  round.sent = (*flood)->Stop();
  round.daemon_cpu = (daemon.CpuSeconds() - cpu_before) / round.busy.seconds;
  std::this_thread::sleep_for(500ms);  // the daemon drains what is still queued
  round.rejected = Rejected(daemon) - rejected_before;
  round.log_growth = daemon.LogBytes() - log_before;
  return round;
}

// (b) The healthy client steps while a thread of this process floods LCM.
void StudyGarbageFlood(const Settings& settings) {
  auto daemon = StartDaemon(settings);
  auto status = daemon->Status();
  if (!status) Die("status", status.error());
  // Steps that lost their request in the flood time out after 2 s (and count as errors).
  auto healthy = HealthyClient::Open(*daemon, "healthy", 2s);
  if (!healthy) Die("healthy client", healthy.error());
  std::printf("## (b) A healthy client during a garbage flood\n\n");
  std::printf(
      "Healthy client as in (a), %s (2 s step timeout). Flood: one thread of this process, its own "
      "LCM instance on %s, target %.0f messages/s, a third each: random bytes (8-507) on the "
      "healthy session's request channel, random bytes on session channels 1-100, step_request_t "
      "for the healthy session signed with a wrong key. Phases of %.0f s alternate. Every "
      "process on the multicast group receives every datagram: the healthy client's own LCM "
      "thread reads the flood too. Daemon CPU: all its threads, in cores.\n\n",
      HealthyPace(settings).c_str(), status->lcm_url.c_str(), settings.flood_rate,
      settings.seconds);
  std::printf(
      "| phase | round | steps | steps/s | p50 ms | p99 ms | max ms | errors | daemon CPU | flood "
      "sent/s | flood thread CPU | rejected by the daemon | daemon log growth | steps/s / "
      "unloaded |\n");
  std::printf(
      "| --- | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: |\n");
  LatencySample unloaded, flooded;
  FloodReport total;
  int64_t rejected_total = 0, log_total = 0;
  std::vector<double> shares;
  for (int round = 1; round <= settings.rounds; ++round) {
    const double cpu_before = daemon->CpuSeconds();
    const LatencySample quiet = (*healthy)->StepFor(settings.seconds, settings.healthy_rate);
    char cpu[160];
    std::snprintf(cpu, sizeof(cpu), "%.0f%% | - | - | - | - | -",
                  100 * (daemon->CpuSeconds() - cpu_before) / quiet.seconds);
    PrintLatencyRow("unloaded", round, quiet, cpu);
    unloaded.Merge(quiet);
    const FloodRound flood = FloodPhase(*daemon, **healthy, *status, settings);
    shares.push_back(flood.busy.StepsPerSecond() / std::max(1e-9, quiet.StepsPerSecond()));
    char extra[160];
    std::snprintf(extra, sizeof(extra), "%.0f%% | %.0f | %.0f%% | %lld | %lld B | %.0f%%",
                  100 * flood.daemon_cpu, flood.sent.Rate(),
                  100 * flood.sent.cpu_seconds / flood.sent.seconds,
                  static_cast<long long>(flood.rejected), static_cast<long long>(flood.log_growth),
                  100 * shares.back());
    PrintLatencyRow("flood", round, flood.busy, extra);
    flooded.Merge(flood.busy);
    total.sent += flood.sent.sent;
    total.seconds += flood.sent.seconds;
    rejected_total += flood.rejected;
    log_total += flood.log_growth;
  }
  const double median = Q(shares, 0.5);
  std::printf(
      "\nFlood: %lld messages in %.1f s (%.0f/s achieved of %.0f/s asked); the daemon counted "
      "%lld of them rejected (%.1f%%); its log grew %lld bytes in all. Healthy steps/s during "
      "the flood against the unloaded phase before it: median **%.0f%%**, from %.0f%% to %.0f%% "
      "(goal: at least 90%%): **%s**. All rounds pooled: %.0f%%. Daemon alive after: %s. "
      "Healthy steps that failed during the floods: %d%s%s.\n\n",
      static_cast<long long>(total.sent), total.seconds, total.Rate(), settings.flood_rate,
      static_cast<long long>(rejected_total),
      100.0 * rejected_total / std::max<int64_t>(1, total.sent), static_cast<long long>(log_total),
      100 * median, 100 * Q(shares, 0), 100 * Q(shares, 1), median >= 0.9 ? "met" : "not met",
      100 * flooded.StepsPerSecond() / std::max(1e-9, unloaded.StepsPerSecond()),
      daemon->Running() ? "yes" : "NO", flooded.errors, flooded.errors ? " (the first: " : "",
      flooded.errors ? (flooded.first_error + ")").c_str() : "");
  if (unloaded.errors > 0) {
    std::printf("Healthy steps that failed in the unloaded phases: %d (the first: %s).\n\n",
                unloaded.errors, unloaded.first_error.c_str());
  }
}

void PrintOpenRow(const char* who, const OpenReport& r) {
  if (!r.not_run.empty()) {
    std::printf("| %s | - | - | - | - | not run: %s |\n", who, r.not_run.c_str());
    return;
  }
  std::printf("| %s | %d | %d | %d | %.3f s | %s |\n", who, r.attempts, r.opened, r.refused,
              r.seconds, r.refusal.empty() ? "-" : r.refusal.c_str());
}

// (c) One user takes what it can; another user then tries 10 opens.
void StudySlots(const Settings& settings, const std::string& self) {
  auto daemon = StartDaemon(settings);
  auto status = daemon->Status();
  if (!status) Die("status", status.error());
  std::vector<std::unique_ptr<client::Client>> held;
  const OpenReport hog = OpenAsFastAsPossible(*daemon, settings.hog_attempts, &held);
  const OpenReport other = OpenAsOtherUser(self, daemon->socket_path(), 10);
  std::printf("## (c) Session slots\n\n");
  std::printf(
      "Daemon limits: %d sessions, %d per user, 20 opens/s per user (bursts of 20). The first "
      "user (uid %d) opens sessions back to back and keeps them; then a second user (uid 65534, "
      "a child process) makes 10 opens.\n\n",
      status->max_sessions, status->max_sessions_per_user, static_cast<int>(geteuid()));
  std::printf("| user | attempts | opened | refused | time | first refusal |\n");
  std::printf("| --- | --: | --: | --: | --: | --- |\n");
  PrintOpenRow("first (hog)", hog);
  PrintOpenRow("second", other);
  std::printf("\n");
}

// (d) Resident size with and after 4 sessions of the heavy scene.
void StudyMemory(const Settings& settings, const Scene& scene) {
  auto daemon = StartDaemon(settings);
  {
    auto warm_up = HealthyClient::Open(*daemon, "warm-up", 10s);
    if (!warm_up) Die("warm-up", warm_up.error());
    (void)(*warm_up)->StepFor(0.5);
  }
  const int64_t baseline = daemon->SettledResidentKiB();
  int64_t with_sessions = 0;
  double seconds = 0;
  {
    std::vector<std::unique_ptr<client::Client>> clients;
    StepRequest bvh;
    bvh.method = Method::kBvh;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 4; ++i) {
      auto client = client::Client::Connect(daemon->Options("large-" + std::to_string(i), 600s));
      if (!client) Die("large session", client.error());
      if (auto ok = UploadInParts(**client, scene); !ok) Die("large upload", ok.error());
      if (auto stepped = (*client)->Step(bvh); !stepped) Die("large step", stepped.error());
      clients.push_back(std::move(*client));
    }
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    with_sessions = daemon->ResidentKiB();
  }
  const int64_t after = daemon->SettledResidentKiB();
  std::printf("## (d) Memory\n\n");
  std::printf(
      "4 sessions, each the scene of (a) (%lld triangles, %lld vertices), uploaded and stepped "
      "once (bvh, contacts) in %.1f s; daemon VmRSS after a warm-up session closed, with the 4 "
      "sessions open, and after they closed.\n\n",
      static_cast<long long>(TriangleCount(scene)), static_cast<long long>(VertexCount(scene)),
      seconds);
  std::printf("| moment | daemon VmRSS |\n| --- | --: |\n");
  std::printf("| baseline | %.1f MiB |\n| 4 large sessions open | %.1f MiB |\n", baseline / 1024.0,
              with_sessions / 1024.0);
  std::printf("| after they closed | %.1f MiB (%+.1f MiB) |\n\n", after / 1024.0,
              (after - baseline) / 1024.0);
}

// A root session of the healthy client: its steps for `seconds` (the first one applies its
// scene, and with it asks the triangle budget for its 1,024 triangles).
std::string RootSteps(const StudyDaemon& daemon, const std::string& name, double seconds) {
  auto healthy = HealthyClient::Open(daemon, name, 60s);
  if (!healthy) return "open refused: " + far::ToString(healthy.error());
  const LatencySample sample = (*healthy)->StepFor(seconds);
  char text[96];
  std::snprintf(text, sizeof(text), "%zu steps served, %d failed", sample.ms.size(), sample.errors);
  return text + (sample.errors ? "; the first: " + sample.first_error : std::string());
}

void PrintHeldRow(const std::string& who, const HeldReport& r) {
  if (!r.not_run.empty()) {
    std::printf("| %s | not run: %s | | |\n", who.c_str(), r.not_run.c_str());
    return;
  }
  std::printf("| %s | %d opened, %d refused, %s triangles in %.2f s%s | %d of %d%s |\n",
              who.c_str(), r.opened, r.refused, Millions(r.triangles).c_str(), r.seconds,
              r.refusal.empty() ? "" : ("; first refusal: " + r.refusal).c_str(), r.alive_after,
              r.opened, r.closed_because.empty() ? "" : ("; " + r.closed_because).c_str());
}

// (e) One uid fills the triangle budget with idle sessions; root then steps.
void StudyTriangleShares(const Settings& settings, const std::string& self) {
  auto daemon = StartDaemon(settings);
  auto hog = HeldSessions::Start(self, daemon->socket_path(), 1001, 4, 2'000'000);
  const std::string collide = RootSteps(*daemon, "root-collide", 0.5);
  const std::string load = RootSteps(*daemon, "root-load", settings.seconds);
  hog->Finish();
  std::printf("## (e) Triangle budget: one user's idle sessions\n\n");
  std::printf(
      "Daemon defaults (8M triangles in all, 2M per session). uid 1001 (a child process) opens 4 "
      "sessions, uploads one object of 2,000,000 degenerate triangles (one vertex, every "
      "triangle (0,0,0)) into each, steps each once (aabb, object PCS) and leaves them idle; "
      "then root opens a session of the healthy client (1,024 triangles) and steps it for "
      "0.5 s (collide), then another for %.0f s (load). Last, uid 1001 steps each of its "
      "sessions once.\n\n",
      settings.seconds);
  std::printf("| who | what | result |\n| --- | --- | --- |\n");
  const HeldReport& r = hog->report();
  if (!r.not_run.empty()) {
    std::printf("| uid 1001 | not run: %s | |\n", r.not_run.c_str());
  } else {
    std::printf(
        "| uid 1001 | 4 sessions of 2M degenerate triangles | %d opened, %s triangles "
        "held after %.2f s%s |\n",
        r.opened, Millions(r.triangles).c_str(), r.seconds,
        r.refusal.empty() ? "" : ("; refused: " + r.refusal).c_str());
  }
  std::printf("| root | collide: a new session, 0.5 s of steps | %s |\n", collide.c_str());
  std::printf("| root | load: a new session, %.0f s of steps | %s |\n", settings.seconds,
              load.c_str());
  std::printf("| uid 1001 | its sessions, stepped once at the end | %d of %d still work%s |\n\n",
              r.alive_after, r.opened,
              r.closed_because.empty() ? "" : ("; " + r.closed_because).c_str());
}

// (f) Four uids take 16 sessions each; root then opens 10.
void StudySlotShares(const Settings& settings, const std::string& self) {
  // Update rings of 256 KiB: 64 sessions take about 1 GiB of shared memory instead of 5 GiB.
  auto daemon = StartDaemon(settings, {"--ring-bytes", "262144"});
  std::vector<std::unique_ptr<HeldSessions>> hogs;
  for (uid_t uid = 1001; uid <= 1004; ++uid)
    hogs.push_back(HeldSessions::Start(self, daemon->socket_path(), uid, 16, 0));
  std::vector<std::unique_ptr<client::Client>> held;
  const OpenReport root = OpenAsFastAsPossible(*daemon, 10, &held);
  const std::string steps =
      held.empty() ? "no session" : RootSteps(*daemon, "root-steps", settings.seconds);
  for (auto& hog : hogs) hog->Finish();
  std::printf("## (f) Session slots: four users\n\n");
  std::printf(
      "Daemon defaults (64 sessions, 16 per user) but update rings of 256 KiB (--ring-bytes "
      "262144: 64 sessions in 1 GiB of this shared machine's memory). "
      "uids 1001-1004 (child processes, one after the other) open 16 sessions each and keep "
      "them idle; then root makes 10 opens and, with one more, steps the healthy client for "
      "%.0f s. Last, each uid steps each of its sessions once.\n\n",
      settings.seconds);
  std::printf("| who | opens | sessions that still work at the end |\n| --- | --- | --- |\n");
  for (auto& hog : hogs) PrintHeldRow("uid " + std::to_string(hog->uid()), hog->report());
  std::printf("| root | %d opened, %d refused in %.2f s%s; then %s | |\n\n", root.opened,
              root.refused, root.seconds,
              root.refusal.empty() ? "" : ("; first refusal: " + root.refusal).c_str(),
              steps.c_str());
}

// (h), (i), (j): issue 41's memory attacks, each against a daemon of its own.
template <typename Runs>
void StudyMemoryAttacks(const Settings& settings, Runs runs) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  if (runs('h')) {
    PrintHoarding(HoardSegments(*StartDaemon(settings), settings.hoard_sessions),
                  settings.hoard_sessions);
  }
  if (runs('i')) {
    PrintKilledClient(KillClientMidStep(*StartDaemon(settings), self, settings.killed),
                      settings.killed);
  }
  if (runs('j'))
    PrintLargeFlood(
        FloodLargeDatagrams(*StartDaemon(settings), settings.flood_bytes, settings.seconds, 3));
}

void PrintLogRow(const char* flood, const LogFloodReport& sent, const LogGrowth& growth) {
  if (!sent.error.empty()) {
    std::printf("| %s | not run: %s | | | | | |\n", flood, sent.error.c_str());
    return;
  }
  const double s = std::max(1e-9, sent.seconds);
  std::printf("| %s | %.1f s | %lld (%lld refused) | %lld | %lld B | %.0f B/s | %s |\n", flood,
              sent.seconds, static_cast<long long>(sent.sent), static_cast<long long>(sent.refused),
              static_cast<long long>(growth.lines), static_cast<long long>(growth.bytes),
              growth.bytes / s, growth.Events().c_str());
}

// (l) One client floods the daemon with what gets a log line, one flood at a time, each
// against a daemon of its own; the log's growth over the flood and the second after it.
void StudyLogFloods(const Settings& settings) {
  std::printf("## (l) The daemon's log during a client's floods\n\n");
  std::printf(
      "Each flood runs %.0f s against a far-daemon of its own (--log-level info), from one "
      "client of uid %d. Step flood: one session of one 16-triangle object sends step requests "
      "(aabb) back to back without waiting for the answers (those past the session's queue or "
      "request rate are refused busy). Open flood: sessions opened back to back, each one that "
      "opens closed at once (those past the open rate are refused busy). Refused opens: the "
      "same against a daemon started with --max-sessions-per-user 1 while the user holds one "
      "session, so that every open is refused. Log growth: from the flood's start to 1 s after "
      "its end.\n\n",
      settings.log_flood_seconds, static_cast<int>(geteuid()));
  std::printf("| flood | time | sent | log lines | log growth | per second | lines by event |\n");
  std::printf("| --- | --: | --: | --: | --: | --: | --- |\n");
  using Flood = LogFloodReport (*)(const StudyDaemon&, double);
  struct Case {
    const char* name;
    Flood flood;
    std::vector<std::string> args;
  };
  for (const Case& c : {Case{"step flood", &StepFlood, {}}, Case{"open flood", &OpenFlood, {}},
                        Case{"refused opens", &OpenFlood, {"--max-sessions-per-user", "1"}}}) {
    auto daemon = StartDaemon(settings, c.args);
    // At its limit: the user holds the one session it may.
    std::unique_ptr<client::Client> held;
    if (!c.args.empty()) {
      auto client = client::Client::Connect(daemon->Options("held"));
      if (!client) Die("held session", client.error());
      held = std::move(*client);
    }
    const int64_t before = daemon->LogBytes();
    const LogFloodReport sent = c.flood(*daemon, settings.log_flood_seconds);
    std::this_thread::sleep_for(1s);
    PrintLogRow(c.name, sent, LogGrowthSince(*daemon, before));
  }
  std::printf("\n");
}

size_t OpenDescriptors(pid_t pid) {
  size_t count = 0;
  for ([[maybe_unused]] const auto& entry :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd"))
    ++count;
  return count;
}

// Connects to `socket` every 20 ms (each connection kept, up to 32) until `stop`.
int KnockUntil(const std::string& socket, const std::atomic<bool>& stop) {
  int knocks = 0;
  std::vector<protocol::LocalConnection> held;
  while (!stop) {
    if (auto connection = protocol::LocalConnection::Connect(socket)) {
      held.push_back(std::move(*connection));
      ++knocks;
    }
    if (held.size() > 32) held.clear();
    std::this_thread::sleep_for(20ms);
  }
  return knocks;
}

// (n) The daemon's RLIMIT_NOFILE lowered to what it has open plus 6, then filled with sessions;
// a client keeps connecting for `seconds`; then the sessions close and a client opens again.
void StudyOutOfDescriptors(const Settings& settings) {
  auto daemon = StartDaemon(settings);
  const rlimit low{OpenDescriptors(daemon->pid()) + 6, 4096};
  if (prlimit(daemon->pid(), RLIMIT_NOFILE, &low, nullptr) != 0)
    Die("prlimit", MakeError(ErrorCode::kUnavailable, std::strerror(errno)));
  std::vector<std::unique_ptr<client::Client>> sessions;
  std::string refusal;
  for (int i = 0; i < 16 && refusal.empty(); ++i) {
    auto client = client::Client::Connect(daemon->Options("filler-" + std::to_string(i)));
    if (client) sessions.push_back(std::move(*client));
    if (!client) refusal = far::ToString(client.error());
  }
  std::atomic<bool> stop{false};
  auto knocks =
      std::async(std::launch::async, [&] { return KnockUntil(daemon->socket_path(), stop); });
  const double cpu_before = daemon->CpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(settings.seconds));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cores = (daemon->CpuSeconds() - cpu_before) / seconds;
  stop = true;
  const int knocked = knocks.get();
  // Descriptors back: how long until a client opens a session again.
  const size_t held = sessions.size();
  sessions.clear();
  const auto freed = std::chrono::steady_clock::now();
  bool reopened = false;
  while (!reopened && std::chrono::steady_clock::now() - freed < 10s)
    reopened = client::Client::Connect(daemon->Options("after")).ok();
  const double recovery_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - freed).count();
  std::printf("## (n) Out of file descriptors\n\n");
  std::printf(
      "far-daemon's RLIMIT_NOFILE lowered (prlimit) to the descriptors it has open plus 6, then "
      "sessions opened until one failed (%s); meanwhile a client connects every 20 ms for %.0f s "
      "(each connection waits in the backlog, or is closed unanswered). Daemon CPU: all its "
      "threads, in cores.\n\n",
      refusal.empty() ? "none did" : refusal.c_str(), settings.seconds);
  std::printf(
      "| sessions held | connections tried | daemon CPU | reopened after the sessions "
      "closed |\n| --: | --: | --: | --- |\n");
  std::printf("| %zu | %d | %.1f%% | %s in %.2f s |\n\n", held, knocked, 100 * cores,
              reopened ? "yes" : "NO", recovery_s);
}

}  // namespace
}  // namespace far::study

int main(int argc, char** argv) {
  using namespace far::study;
  EnterNetworkNamespace(argc, argv, FAR_NETNS_RUN_PATH);
  if (argc == 4 && std::strcmp(argv[1], kOtherUserFlag) == 0)
    return OtherUserMain(argv[2], std::atoi(argv[3]));
  if (argc >= 2 && std::strcmp(argv[1], kKilledClientFlag) == 0)
    return KilledClientMain(argc, argv);
  Settings settings;
  if (argc == 5 && std::strcmp(argv[1], kHoldAsUserFlag) == 0)
    return HoldAsUserMain(argv[2], std::atoi(argv[3]), std::atoll(argv[4]));
  CLI::App app{"far_hardening_study: issue 10's hardening, measured (bench/RESULTS.md)"};
  app.add_option("--seconds", settings.seconds, "length of one phase of (a) and (b)")
      ->capture_default_str();
  app.add_option("--rounds", settings.rounds, "unloaded + loaded phase pairs of (a) and (b)")
      ->capture_default_str();
  app.add_option("--triangles", settings.triangles, "the heavy scene of (a) and (d), at most")
      ->capture_default_str();
  app.add_option("--flood-rate", settings.flood_rate, "garbage messages per second in (b)")
      ->capture_default_str();
  app.add_option("--hog-attempts", settings.hog_attempts, "opens of the first user in (c)")
      ->capture_default_str();
  app.add_option("--log-flood-seconds", settings.log_flood_seconds, "length of each flood of (l)")
      ->capture_default_str();
  app.add_option("--parts", settings.parts,
                 "which parts to run (letters of abcdefghijln; e, f, g: issue 41's fair shares and "
                 "lost datagrams; h, i, "
                 "j: its memory attacks; l, n: its log floods and descriptors)")
      ->capture_default_str();
  app.add_option("--heavy-method", settings.heavy_method, "the heavy client's method in (a)")
      ->capture_default_str()
      ->check([](const std::string& name) {
        return far::ParseMethod(name) ? "" : "unknown method (" + far::MethodNames() + ")";
      });
  app.add_option("--heavy-distance", settings.heavy_distance,
                 "> 0: the heavy client's steps look for contacts among all triangles this close "
                 "to a partner object (a wider search: more work)")
      ->capture_default_str();
  app.add_option("--healthy-rate", settings.healthy_rate,
                 "the healthy client's steps per second in (a) and (b), as a simulator's fixed "
                 "rate (0: back to back)")
      ->capture_default_str();
  app.add_option("--hoard-sessions", settings.hoard_sessions, "sessions opened and left in (h)")
      ->capture_default_str();
  app.add_option("--killed-triangles", settings.killed.triangles,
                 "the scene of the client killed mid-step in (i)")
      ->capture_default_str();
  app.add_option("--killed-neighbour", settings.killed.neighbour_triangles,
                 "the scene of another client stepping beside it in (i) (0: none)")
      ->capture_default_str();
  app.add_option("--killed-method", settings.killed.method, "their steps' method in (i)")
      ->capture_default_str();
  app.add_option("--killed-resolution", settings.killed.resolution,
                 "their steps' resolution in (i)")
      ->capture_default_str();
  app.add_option("--killed-after", settings.killed.kill_after_s,
                 "seconds the client's step runs before (i)'s kill")
      ->capture_default_str();
  app.add_option("--flood-bytes", settings.flood_bytes, "bytes per datagram in (j)")
      ->capture_default_str();
  app.add_option("--loss-trials", settings.loss_trials, "steps per loss case of (g)")
      ->capture_default_str();
  app.add_option("--daemon", settings.daemon, "far-daemon to start")->capture_default_str();
  app.add_option("--daemon-arg", settings.daemon_args,
                 "an argument added to every far-daemon's command line (repeat: --daemon-arg "
                 "--threads --daemon-arg 1)")
      ->allow_extra_args(false);
  CLI11_PARSE(app, argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  PrintHeader(argc, argv, settings);
  const auto runs = [&](char part) { return settings.parts.find(part) != std::string::npos; };
  far::Scene scene;
  if (runs('a') || runs('d')) scene = LargestScene(settings.triangles);
  if (runs('a')) StudyHeavyClient(settings, scene);
  if (runs('b')) StudyGarbageFlood(settings);
  if (runs('c')) StudySlots(settings, std::filesystem::read_symlink("/proc/self/exe").string());
  if (runs('d')) StudyMemory(settings, scene);
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  if (runs('e')) StudyTriangleShares(settings, self);
  if (runs('f')) StudySlotShares(settings, self);
  if (runs('g')) {
    StudyLostDatagrams({settings.daemon, settings.loss_trials, settings.flood_rate,
                        settings.seconds, settings.rounds, settings.healthy_rate});
  }
  StudyMemoryAttacks(settings, runs);
  if (runs('l')) StudyLogFloods(settings);
  if (runs('n')) StudyOutOfDescriptors(settings);
  return 0;
}
