// far-client --daemon auto on a machine with two daemons, as a node with two GPUs has: each
// client finds the daemon of the GPU its job was given without being told a name, the two
// daemons serve their clients fairly, and clients whose job names no GPU spread over both.
// The daemons run on llvmpipe and stand in for GPUs 0 and 1 with --serves-gpus (on a GPU node
// the names come from the EGL device: far::GpuIdentifiers, GpuIdentityTest).

#include <algorithm>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "daemon_fixture.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace far::integration {
namespace {

using nlohmann::json;

class AutoDaemonTest : public DaemonTest {
 protected:
  void SetUp() override {
    ::setenv("FAR_SOCKET_DIR", dir_.path().c_str(), 1);
    for (const char* gpu : {"0", "1"}) {
      ASSERT_NE(StartDaemon({"--name", std::string("gpu-") + gpu, "--serves-gpus", gpu,
                             "--max-sessions-per-user", "64"}),
                nullptr);
    }
  }
  void TearDown() override {
    DaemonTest::TearDown();
    ::unsetenv("FAR_SOCKET_DIR");
  }

  // far-client status --all --json: every daemon in the test's socket directory.
  json AllStatus() {
    const ProcessResult run = RunFarClient({"status", "--all", "--json"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.exit_code == 0 ? json::parse(run.out) : json::array();
  }

  // A load client that finds its daemon itself: $FAR_DAEMON=auto, its job's GPU in $FAR_GPUS
  // ("" for none), stepping for `seconds`.
  std::unique_ptr<ChildProcess> SpawnClient(const std::string& gpu, double seconds) {
    std::vector<std::string> argv = {"/usr/bin/env", "FAR_DAEMON=auto"};
    if (!gpu.empty()) argv.push_back("FAR_GPUS=" + gpu);
    for (std::string arg :
         {std::string(FAR_CLIENT_PATH), std::string("--connect-timeout"), std::string("20s"),
          std::string("load"), std::string("--clients"), std::string("1"), std::string("--steps"),
          std::string("0"), std::string("--seconds"), std::to_string(seconds),
          std::string("--method"), std::string("bvh"), std::string("--client-cpu-ms"),
          std::string("2"), std::string("--json")})
      argv.push_back(arg);
    auto child = ChildProcess::Spawn(argv);
    EXPECT_TRUE(child.ok()) << ToString(child.error());
    return child.ok() ? std::move(*child) : nullptr;
  }

  TempDir dir_;
};

// Sessions open on each daemon, by its name.
std::map<std::string, int> OpenSessions(const json& all) {
  std::map<std::string, int> open;
  for (const json& daemon : all)
    open[daemon.value("daemon_name", "?")] = daemon.value("sessions_open", 0);
  return open;
}

TEST_F(AutoDaemonTest, ThirtyTwoClientsFindTheirGpusDaemonAndAreServedFairly) {
  constexpr int kClients = 32;
  // Long enough that a session's count is a few hundred steps: over a few seconds the
  // scheduling noise of 70 processes on 2 cores alone spreads 32 counts by +-20%. Each client
  // spends 2 ms of CPU per step on its own side, as a simulator's physics would, so that its
  // steps are paced by CPU time (which the kernel shares fairly), not by which process wins the
  // race to wake up (a tight loop of bare round trips measured 1.09-1.28 over 20 s; paced,
  // 1.10-1.17 over 12 s).
  constexpr int kWindowSeconds = 20;
  std::map<int, std::string> gpu_of_pid;
  std::vector<std::unique_ptr<ChildProcess>> clients;
  for (int i = 0; i < kClients; ++i) {
    const std::string gpu = std::to_string(i % 2);
    clients.push_back(SpawnClient(gpu, kWindowSeconds + 14));
    ASSERT_NE(clients.back(), nullptr);
    gpu_of_pid[clients.back()->pid()] = gpu;
  }
  ASSERT_TRUE(WaitUntil(
      [&] {
        const auto open = OpenSessions(AllStatus());
        return open.count("gpu-0") && open.at("gpu-0") == kClients / 2 && open.count("gpu-1") &&
               open.at("gpu-1") == kClients / 2;
      },
      std::chrono::seconds(20)))
      << AllStatus().dump(2);

  // Steps per session over a window in which all 32 step: the first status to the second.
  const auto steps_of = [](const json& all) {
    std::map<std::pair<std::string, int64_t>, int64_t> steps;
    for (const json& daemon : all)
      for (const json& session : daemon.at("sessions"))
        steps[{daemon.at("daemon_name"), session.at("id")}] = session.at("steps");
    return steps;
  };
  const json first = AllStatus();
  std::this_thread::sleep_for(std::chrono::seconds(kWindowSeconds));
  const json second = AllStatus();

  int checked = 0;
  for (const json& daemon : second) {
    const std::vector<std::string> gpus = daemon.at("gpu_names");
    ASSERT_EQ(gpus.size(), 1u) << daemon.dump();
    for (const json& session : daemon.at("sessions")) {
      const int pid = session.at("pid");
      ASSERT_TRUE(gpu_of_pid.count(pid)) << "a session of no client of this test: " << pid;
      EXPECT_EQ(gpu_of_pid.at(pid), gpus[0]) << "client " << pid << " of GPU " << gpu_of_pid.at(pid)
                                             << " is on " << daemon.at("daemon_name");
      ++checked;
    }
  }
  EXPECT_EQ(checked, kClients);

  const auto before = steps_of(first), after = steps_of(second);
  std::map<std::string, std::vector<int64_t>> by_daemon;
  std::vector<int64_t> all_windows;
  for (const auto& [session, steps] : after) {
    ASSERT_TRUE(before.count(session));
    const int64_t window = steps - before.at(session);
    by_daemon[session.first].push_back(window);
    all_windows.push_back(window);
  }
  for (auto& [daemon, windows] : by_daemon) {
    std::sort(windows.begin(), windows.end());
    std::printf("%s: steps per session in the window, sorted:", daemon.c_str());
    for (int64_t steps : windows) std::printf(" %lld", static_cast<long long>(steps));
    std::printf("\n");
  }
  // Fair: every session within 15% of the median session. Measured against the median, not as
  // max/min: the extremes of 32 counts on 2 shared cores spread by scheduling noise alone (max/min
  // 1.25 in a run whose every session was within 12% of the median), while a session the daemon
  // starved or favoured stands out from the median all the same.
  std::sort(all_windows.begin(), all_windows.end());
  const int64_t least = all_windows.front(), most = all_windows.back();
  const double median =
      0.5 * double(all_windows[(all_windows.size() - 1) / 2] + all_windows[all_windows.size() / 2]);
  std::printf(
      "32 clients on 2 daemons: steps per session in %d s: min %lld median %.1f max %lld "
      "(%.3f .. %.3f of the median)\n",
      kWindowSeconds, static_cast<long long>(least), median, static_cast<long long>(most),
      double(least) / median, double(most) / median);
  EXPECT_GT(least, 0);
  EXPECT_GE(double(least), 0.85 * median);
  EXPECT_LE(double(most), 1.15 * median);

  for (auto& client : clients) {
    const std::optional<int> code = client->Wait(std::chrono::seconds(40));
    EXPECT_EQ(code, 0);
  }
}

TEST_F(AutoDaemonTest, ClientsOfAJobWithoutGpusGoToTheLeastLoadedDaemon) {
  // One client after another, each once the one before has its session: each sees the loads
  // as they are, so the least loaded daemon alternates. (Clients that start together see the
  // same loads and spread by process id instead: no count is promised then.)
  constexpr int kClients = 16;
  std::vector<std::unique_ptr<ChildProcess>> clients;
  std::map<std::string, int> open;
  for (int i = 0; i < kClients; ++i) {
    clients.push_back(SpawnClient("", 120));  // still stepping when the last one starts
    ASSERT_NE(clients.back(), nullptr);
    ASSERT_TRUE(WaitUntil(
        [&] {
          open = OpenSessions(AllStatus());
          return open["gpu-0"] + open["gpu-1"] == i + 1;
        },
        std::chrono::seconds(20)))
        << AllStatus().dump(2);
    EXPECT_LE(std::abs(open["gpu-0"] - open["gpu-1"]), 1) << "after client " << i;
  }
  std::printf("16 clients without a GPU: gpu-0 %d, gpu-1 %d\n", open["gpu-0"], open["gpu-1"]);
  // Their work is done: SIGKILL (the destructor), and the daemons close their sessions.
}

}  // namespace
}  // namespace far::integration
