// The daemon's one catch at dispatch: a handler that throws becomes one error (counted as
// "internal", logged once) and the daemon goes on serving. The daemon runs in this process,
// with a test hook that throws, on the test's private multicast bus.
#include <atomic>
#include <chrono>
#include <thread>

#include "daemon.h"
#include "daemon_process.h"
#include "integration_scenes.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"

namespace far::integration {
namespace {

TEST(DispatchTest, AHandlerThatThrowsIsAnErrorAndTheDaemonKeepsServing) {
  TempDir dir;
  server::DaemonConfig config;
  config.lcm_url = TestLcmUrl();
  config.socket_path = (dir.path() / "far.sock").string();
  config.log_level = "warn";
  config.gpu_cost_cache = FAR_TEST_GPU_COST_CACHE;  // the tree's, as DaemonProcess passes it
  std::atomic<bool> armed{false};
  std::atomic<int> thrown{0};
  server::DaemonTestHooks hooks;
  hooks.before_message = [&](std::string_view) {
    if (armed.exchange(false)) {
      ++thrown;
      throw std::runtime_error("boom");
    }
  };
  auto daemon = server::Daemon::Create(config, hooks);
  ASSERT_TRUE(daemon) << far::ToString(daemon.error());
  std::thread serving([&] { EXPECT_TRUE((*daemon)->Run()); });

  client::ClientOptions options;
  options.socket_path = config.socket_path;
  options.connect_timeout = std::chrono::seconds(10);
  options.timeout = std::chrono::milliseconds(1500);
  auto client = client::Client::Connect(options);
  ASSERT_TRUE(client) << far::ToString(client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE((*client)->LoadScene(scene).ok());
  StepRequest request;
  request.method = Method::kBvh;
  // The step's request throws inside the handler: no answer, no crash. The client, hearing
  // nothing of the step, sends it again 200 ms later, and that one is answered; the failure
  // was counted once, as "internal".
  armed = true;
  auto answered = (*client)->Step(request);
  ASSERT_EQ(thrown.load(), 1);
  ASSERT_TRUE(answered) << far::ToString(answered.error());
  EXPECT_EQ(answered->contacts, ReferenceContacts(scene.objects));
  auto status = client::Client::Status(options);
  ASSERT_TRUE(status) << far::ToString(status.error());
  int64_t internal = 0;
  for (const auto& [kind, count] : status->errors_by_kind) {
    if (kind == "internal") internal = count;
  }
  EXPECT_EQ(internal, 1);
  client->reset();
  (*daemon)->Stop();
  serving.join();
}

}  // namespace
}  // namespace far::integration
