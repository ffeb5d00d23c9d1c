// A daemon out of file descriptors (EMFILE): its RLIMIT_NOFILE lowered to what it has open plus
// a few, then filled with sessions. accept() then fails and the connection stays in the
// backlog, so the listener stays readable: the socket thread used to poll it in a loop at half
// a core (issue 41). Now each such accept closes one waiting connection unanswered and the
// listener rests for 100 ms; the daemon serves again as soon as descriptors are free.
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/local_socket.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// CPU time of process `pid` (all threads, user + system), in seconds.
double CpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Fields after the command (which may hold spaces) start after its closing parenthesis.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

size_t OpenDescriptors(pid_t pid) {
  size_t count = 0;
  for ([[maybe_unused]] const auto& entry :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd"))
    ++count;
  return count;
}

using OutOfDescriptorsTest = DaemonTest;

TEST_F(OutOfDescriptorsTest, TheDaemonRestsWhileOutOfDescriptorsAndServesWhenTheyAreBack) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  const rlimit low{OpenDescriptors(daemon->pid()) + 6, 4096};
  ASSERT_EQ(prlimit(daemon->pid(), RLIMIT_NOFILE, &low, nullptr), 0) << std::strerror(errno);
  // Sessions until the daemon has no descriptor left for another.
  std::vector<std::unique_ptr<client::Client>> sessions;
  for (int i = 0; i < 12; ++i) {
    auto client = client::Client::Connect(TestClientOptions("filler-" + std::to_string(i)));
    if (!client) break;
    sessions.push_back(std::move(*client));
  }
  ASSERT_LT(sessions.size(), 12u) << "the daemon never ran out of descriptors";

  // Connections keep coming while it is out (each would wait in the backlog).
  std::atomic<bool> stop{false};
  auto knocks = std::async(std::launch::async, [&] {
    std::vector<protocol::LocalConnection> held;
    while (!stop) {
      auto connection = protocol::LocalConnection::Connect(daemon->socket_path());
      if (connection) held.push_back(std::move(*connection));
      if (held.size() > 32) held.clear();
      std::this_thread::sleep_for(20ms);
    }
    return held.size();
  });
  const double cpu_before = CpuSeconds(daemon->pid());
  const auto start = Clock::now();
  std::this_thread::sleep_for(3s);
  const double cores = (CpuSeconds(daemon->pid()) - cpu_before) /
                       std::chrono::duration<double>(Clock::now() - start).count();
  stop = true;
  knocks.get();
  EXPECT_LT(cores, 0.1) << "the daemon's CPU while out of descriptors, in cores";
  RecordProperty("daemon_cores_out_of_descriptors_percent", static_cast<int>(100 * cores));

  // Descriptors back: a new client is served.
  sessions.clear();
  std::unique_ptr<client::Client> after;
  ASSERT_TRUE(WaitUntil(
      [&] {
        auto client = client::Client::Connect(TestClientOptions("after"));
        if (client) after = std::move(*client);
        return after != nullptr;
      },
      5s));
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE(after->LoadScene(scene).ok());
  auto stepped = after->Step(SmallRequest());
  ASSERT_TRUE(stepped.ok()) << far::ToString(stepped.error());
  EXPECT_EQ(stepped->contacts, ReferenceContacts(scene.objects));
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status.ok());
  int64_t out_of_descriptors = 0;
  for (const auto& [kind, count] : status->errors_by_kind) {
    if (kind == "out_of_descriptors") out_of_descriptors = count;
  }
  EXPECT_GT(out_of_descriptors, 0) << "connections closed unanswered, counted in status";
}

}  // namespace
}  // namespace far::integration
