// Where the driver gives the batcher no context of its own, far-daemon says so and serves the
// gpu method as with --gpu-batch false: each session issues its own steps, with the same
// answers (docs/daemon.md, "The GL lock and the gpu method"). The daemon runs in this process,
// with a test hook that makes the batcher's context fail, and its log is read from a sink.
#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "daemon.h"
#include "daemon_process.h"
#include "integration_scenes.h"
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include "far/client/client.h"

namespace far::integration {
namespace {

// Every line the default logger writes while it lives.
class LogCapture {
 public:
  LogCapture() { spdlog::default_logger()->sinks().push_back(sink_); }
  ~LogCapture() {
    auto& sinks = spdlog::default_logger()->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), sink_), sinks.end());
  }
  std::string Text() const {
    std::string text;
    for (const std::string& line : sink_->last_formatted()) text += line;
    return text;
  }

 private:
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink_ =
      std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(256);
};

TEST(GpuBatchFallbackTest, WithoutASecondContextEachSessionStepsTheGpuMethodItself) {
  TempDir dir;
  server::DaemonConfig config;
  config.lcm_url = TestLcmUrl();
  config.socket_path = (dir.path() / "far.sock").string();
  config.gpu_cost_cache = FAR_TEST_GPU_COST_CACHE;
  ASSERT_TRUE(config.gpu_batch) << "the default";
  server::DaemonTestHooks hooks;
  hooks.batcher_context_fails = true;
  LogCapture log;
  auto daemon = server::Daemon::Create(config, hooks);
  ASSERT_TRUE(daemon) << far::ToString(daemon.error());
  std::thread serving([&] { EXPECT_TRUE((*daemon)->Run()); });

  client::ClientOptions options;
  options.socket_path = config.socket_path;
  options.connect_timeout = std::chrono::seconds(30);
  // Two sessions, so that the steps really are each session's own, one after the other.
  for (uint64_t seed : {kHealthySeed, kHealthySeed + 1}) {
    auto client = client::Client::Connect(options);
    ASSERT_TRUE(client) << far::ToString(client.error());
    Scene scene;
    scene.objects = ContactSoup(seed);
    ASSERT_TRUE((*client)->LoadScene(scene).ok());
    StepRequest request;
    request.method = Method::kGpu;
    for (int step = 0; step < 2; ++step) {
      auto answered = (*client)->Step(request);
      ASSERT_TRUE(answered) << far::ToString(answered.error());
      EXPECT_EQ(answered->contacts, ReferenceContacts(scene.objects)) << "seed " << seed;
    }
  }
  (*daemon)->Stop();
  serving.join();
  const std::string text = log.Text();
  EXPECT_NE(text.find("event=gpu_batch_unavailable reason=\"no second context (test hook)\""),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("gpu_batch=false"), std::string::npos) << "in daemon_ready:\n" << text;
}

}  // namespace
}  // namespace far::integration
