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
  server::DaemonConfig config;
  config.lcm_url = TestLcmUrl();
  config.log_level = "warn";
  std::atomic<int> thrown{0};
  server::DaemonTestHooks hooks;
  hooks.before_message = [&](std::string_view channel) {
    if (channel == protocol::kStatusChannel && thrown++ == 0) throw std::runtime_error("boom");
  };
  auto daemon = server::Daemon::Create(config, hooks);
  ASSERT_TRUE(daemon) << far::ToString(daemon.error());
  std::thread serving([&] { EXPECT_TRUE((*daemon)->Run()); });

  // The first status request throws inside the handler: no answer, no crash.
  const auto first = client::Client::Status(config.lcm_url, std::chrono::milliseconds(1500));
  // (the daemon may not be up yet for the very first request; ask until one throws)
  for (int i = 0; i < 20 && thrown == 0; ++i) {
    (void)client::Client::Status(config.lcm_url, std::chrono::milliseconds(250));
  }
  ASSERT_GE(thrown.load(), 1);
  // The next one is answered and counts the failure once, as "internal".
  auto status = client::Client::Status(config.lcm_url, std::chrono::milliseconds(3000));
  ASSERT_TRUE(status) << far::ToString(status.error());
  int64_t internal = 0;
  for (const auto& [kind, count] : status->errors_by_kind) {
    if (kind == "internal") internal = count;
  }
  EXPECT_EQ(internal, 1);
  // And a well-behaved client still gets exact answers.
  EXPECT_TRUE(HealthyClientSteps("after-throw"));
  (*daemon)->Stop();
  serving.join();
  (void)first;
}

}  // namespace
}  // namespace far::integration
