#include "lost_datagrams.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "garbage_flood.h"
#include "study_daemon.h"

#include "far/base/quantile.h"
#include "far/client/internal/client_access.h"
#include "far/scenes/scenes.h"

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;
using client::internal::Datagram;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// A light client on the default step timeout (60 s): 8 clusters of 128 triangles that drift.
class LossyClient {
 public:
  static std::unique_ptr<LossyClient> Open(const StudyDaemon& daemon) {
    auto client = client::Client::Connect(daemon.Options("lossy"));
    if (!client) {
      std::fprintf(stderr, "lost datagrams: %s\n", far::ToString(client.error()).c_str());
      return nullptr;
    }
    auto lossy = std::unique_ptr<LossyClient>(new LossyClient(std::move(*client)));
    for (const SceneObject& o : lossy->objects_) {
      if (!lossy->client_->AddObject(o.id, o.mesh, Motion::kRigid, o.X_WO)) return nullptr;
    }
    return lossy;
  }
  // One step: how long it took to answer or to fail, and its error when it failed.
  struct Outcome {
    double seconds = 0;
    std::optional<Error> error;
  };
  Outcome Step() {
    for (const SceneObject& o : objects_) {
      Pose pose = o.X_WO;
      pose.translation.x() += 0.05 * std::sin(0.01 * static_cast<double>(step_) + o.id);
      if (auto ok = client_->SetPose(o.id, pose); !ok) return {0, ok.error()};
    }
    ++step_;
    const auto start = Clock::now();
    auto result = client_->Step(request_);
    const double seconds = Seconds(Clock::now() - start);
    if (!result) return {seconds, result.error()};
    return {seconds, std::nullopt};
  }
  int64_t next_step() const { return step_; }
  int64_t session_id() const { return client_->session_id(); }

 private:
  explicit LossyClient(std::unique_ptr<client::Client> client)
      : client_(std::move(client)), objects_(scenes::RandomSoup(17, 8, 128, 2.0, 0.3)) {
    request_.method = Method::kBvh;
  }
  std::unique_ptr<client::Client> client_;
  std::vector<SceneObject> objects_;
  StepRequest request_;
  int64_t step_ = 0;
};

int64_t StepsRun(const StudyDaemon& daemon) {
  auto status = daemon.Status();
  return status ? status->steps_total : -1;
}

// The datagrams the kernel dropped for want of receive buffer, over every UDP socket of this
// network namespace (the study's and the daemon's): the drops column of /proc/net/udp.
int64_t KernelUdpDrops() {
  std::ifstream udp("/proc/net/udp");
  std::string line;
  std::getline(udp, line);  // header
  int64_t drops = 0;
  while (std::getline(udp, line)) {
    std::istringstream fields(line);
    std::string field, last;
    while (fields >> field) last = field;
    drops += std::atoll(last.c_str());
  }
  return drops;
}

struct LossCase {
  const char* name;
  const char* kind;  // what is lost: "request" (outgoing) or "reply" / "status" (incoming)
  int count;         // how many of them for the step (the first ones)
};

// Each trial loses `what` for one step of the client; the time to complete that step.
void RunCase(const StudyDaemon& daemon, LossyClient& client, const LossCase& what, int trials) {
  std::vector<double> seconds;
  int errors = 0;
  std::string first_error;
  const int64_t before = StepsRun(daemon);
  for (int trial = 0; trial < trials; ++trial) {
    const int64_t step = client.next_step();
    auto left = std::make_shared<std::atomic<int>>(what.count);
    const bool outgoing = std::string(what.kind) == "request";
    client::internal::SetDatagramLoss([=](const Datagram& d) {
      if (d.outgoing != outgoing || d.kind != what.kind || d.step_id != step) return false;
      return left->fetch_sub(1) > 0;
    });
    const auto outcome = client.Step();
    client::internal::SetDatagramLoss({});
    seconds.push_back(outcome.seconds);
    if (outcome.error) {
      ++errors;
      if (first_error.empty()) first_error = far::ToString(*outcome.error);
    }
  }
  const int64_t run = StepsRun(daemon) - before;
  std::sort(seconds.begin(), seconds.end());
  std::printf("| %s | %d | %.3f | %.3f | %d | %lld | %s |\n", what.name, trials,
              seconds.empty() ? 0.0 : Quantile(seconds, 0.5),
              seconds.empty() ? 0.0 : seconds.back(), errors, static_cast<long long>(run),
              first_error.empty() ? "-" : first_error.c_str());
}

void StudyLossCases(const StudyDaemon& daemon, LossyClient& client, int trials) {
  std::printf("## (g) Lost datagrams: a step whose request or reply is lost\n\n");
  std::printf(
      "A light client (8 rigid clusters of 128 triangles, method bvh, contacts) on the default "
      "step timeout (60 s). In each trial one of its steps loses what the case says at the "
      "client library's loss seam (as LCM over UDP would); the time is the step's round trip, "
      "to its answer or to its error. "
      "Steps run: the daemon's steps_total over the trials (one per step asked when no step runs "
      "twice).\n\n");
  std::printf("| lost | steps | median s | max s | errors | steps run | first error |\n");
  std::printf("| --- | --: | --: | --: | --: | --: | --- |\n");
  const LossCase cases[] = {
      {"nothing", "none", 0},
      {"the request, once", "request", 1},
      {"the request, 3 times", "request", 3},
      {"the reply, once", "reply", 1},
      {"every status (queued, started, stages)", "status", 1000},
  };
  for (const LossCase& what : cases) RunCase(daemon, client, what, trials);
  std::printf("\n");
}

// The client steps at its rate while this process floods LCM with forged requests.
void StudyFlood(const StudyDaemon& daemon, LossyClient& client,
                const LostDatagramSettings& settings) {
  auto status = daemon.Status();
  if (!status) return;
  std::printf("## (g) Lost datagrams: a light client during a forged-request flood\n\n");
  std::printf(
      "The client of the table above (default 60 s step timeout), one step every %.1f ms, while "
      "a thread of this process floods %s at %.0f messages/s (part (b)'s mix: random bytes, "
      "forged step requests); %d phases of %.0f s. Kernel drops: the drops column of "
      "/proc/net/udp over the phase (every UDP socket of the study's network namespace).\n\n",
      1000 / settings.healthy_rate, status->lcm_url.c_str(), settings.flood_rate,
      settings.flood_rounds, settings.flood_seconds);
  std::printf("Every step counts, answered or failed (at its timeout).\n\n");
  std::printf(
      "| phase | steps | p50 ms | p99 ms | max ms | steps over 1 s | errors | flood sent/s | "
      "kernel drops | steps run / asked |\n| --: | --: | --: | --: | --: | --: | --: | --: | --: "
      "| --: |\n");
  for (int round = 1; round <= settings.flood_rounds; ++round) {
    const int64_t drops = KernelUdpDrops(), run = StepsRun(daemon);
    auto flood = GarbageFlood::Start(status->lcm_url, status->channel_prefix, client.session_id(),
                                     settings.flood_rate);
    if (!flood) return;
    std::vector<double> ms;
    int errors = 0, asked = 0;
    const auto start = Clock::now();
    auto next = start;
    const auto period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1 / settings.healthy_rate));
    while (Seconds(Clock::now() - start) < settings.flood_seconds) {
      std::this_thread::sleep_until(next);
      next = std::max(next + period, Clock::now());
      ++asked;
      const auto step = client.Step();
      ms.push_back(1000 * step.seconds);
      if (step.error) ++errors;
    }
    const FloodReport sent = (*flood)->Stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    std::sort(ms.begin(), ms.end());
    const auto slow = std::count_if(ms.begin(), ms.end(), [](double m) { return m > 1000; });
    std::printf("| %d | %zu | %.2f | %.2f | %.1f | %lld | %d | %.0f | %lld | %lld / %d |\n", round,
                ms.size(), ms.empty() ? 0 : Quantile(ms, 0.5), ms.empty() ? 0 : Quantile(ms, 0.99),
                ms.empty() ? 0 : ms.back(), static_cast<long long>(slow), errors, sent.Rate(),
                static_cast<long long>(KernelUdpDrops() - drops),
                static_cast<long long>(StepsRun(daemon) - run), asked);
  }
  std::printf("\n");
}

}  // namespace

void StudyLostDatagrams(const LostDatagramSettings& settings) {
  auto daemon = StudyDaemon::Start(settings.daemon, {});
  if (!daemon) {
    std::fprintf(stderr, "lost datagrams: %s\n", far::ToString(daemon.error()).c_str());
    return;
  }
  auto client = LossyClient::Open(**daemon);
  if (!client) return;
  if (client->Step().error) return;  // the first step makes the session's pipeline
  StudyLossCases(**daemon, *client, settings.trials);
  if (settings.flood_rounds > 0) StudyFlood(**daemon, *client, settings);
}

}  // namespace far::study
