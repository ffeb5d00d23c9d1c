// Several daemons on one machine (one per GPU): each takes its own name, which gives it its
// socket (<dir>/<name>.sock) and its LCM channel prefix; clients pick one with --daemon NAME;
// status names the EGL device; --gpu N takes EGL device N or fails saying what exists. Run with
// two daemons on llvmpipe's EGL device 0 (EGL_MESA_device_software), which every Mesa offers.

#include <cstdlib>
#include <string>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "far/io/scene_io.h"
#include "far/protocol/channels.h"

namespace far::integration {
namespace {

using nlohmann::json;

// Daemons and clients of this test find sockets in a folder of their own ($FAR_SOCKET_DIR).
class TwoDaemonsTest : public DaemonTest {
 protected:
  void SetUp() override { ::setenv("FAR_SOCKET_DIR", dir_.path().c_str(), 1); }
  void TearDown() override {
    DaemonTest::TearDown();
    ::unsetenv("FAR_SOCKET_DIR");
  }

  json Status(const std::string& name) {
    const ProcessResult run = RunFarClient({"--daemon", name, "status", "--json"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.exit_code == 0 ? json::parse(run.out) : json::object();
  }

  TempDir dir_;
};

TEST_F(TwoDaemonsTest, ClientsChooseADaemonByNameAndEachKeepsItsOwnSessions) {
  ASSERT_NE(StartDaemon({"--name", "alpha", "--gpu", "0"}), nullptr);
  ASSERT_NE(StartDaemon({"--name", "beta", "--gpu", "0"}), nullptr);
  EXPECT_EQ(daemons_[0]->socket_path(), (dir_.path() / "alpha.sock").string());

  const auto path = dir_.path() / "soup.json";
  Scene scene;
  scene.objects = ContactSoup(5);
  ASSERT_TRUE(WriteScene(scene, path).ok());
  const ProcessResult collided =
      RunFarClient({"--daemon", "alpha", "collide", path.string(), "--method", "bvh"});
  ASSERT_EQ(collided.exit_code, 0) << collided.err;
  EXPECT_FALSE(json::parse(collided.out).at("contacts").empty());
  for (int i = 0; i < 2; ++i) {
    const ProcessResult played =
        RunFarClient({"--daemon", "beta", "play", path.string(), "--method", "aabb"});
    ASSERT_EQ(played.exit_code, 0) << played.err;
  }

  const json alpha = Status("alpha"), beta = Status("beta");
  EXPECT_EQ(alpha.value("daemon_name", ""), "alpha");
  EXPECT_EQ(beta.value("daemon_name", ""), "beta");
  EXPECT_EQ(alpha.value("channel_prefix", ""), "FAR_ALPHA_");
  EXPECT_EQ(beta.value("channel_prefix", ""), "FAR_BETA_");
  // Each daemon ran its own clients' steps and nobody else's.
  EXPECT_EQ(alpha.value("steps_total", -1), 1) << alpha.dump();
  EXPECT_EQ(beta.value("steps_total", -1), 2) << beta.dump();
  // Status names the device --gpu picked.
  EXPECT_EQ(alpha.value("gl_device", "").rfind("EGL device 0 ", 0), 0u) << alpha.dump();
  // No daemon by that name: said at once, naming the socket looked for.
  const ProcessResult nobody = RunFarClient({"--daemon", "gamma", "ping"});
  EXPECT_NE(nobody.exit_code, 0);
  EXPECT_NE(nobody.err.find((dir_.path() / "gamma.sock").string()), std::string::npos)
      << nobody.err;
}

TEST_F(TwoDaemonsTest, ANameInUseIsRefusedAndAMissingGpuIsAnError) {
  ASSERT_NE(StartDaemon({"--name", "alpha"}), nullptr);
  // (Run directly: DaemonProcess::Start would find the first daemon answering.)
  const ProcessResult same = RunProcess(
      {FAR_DAEMON_PATH, "--name", "alpha", "--lcm-url", TestLcmUrl()}, std::chrono::seconds(10));
  EXPECT_NE(same.exit_code, 0);
  EXPECT_NE(same.err.find("alpha.sock"), std::string::npos) << same.out << same.err;
  // The first one still serves.
  EXPECT_EQ(Status("alpha").value("daemon_name", ""), "alpha");

  const ProcessResult missing =
      RunProcess({FAR_DAEMON_PATH, "--name", "beta", "--gpu", "99", "--lcm-url", TestLcmUrl()},
                 std::chrono::seconds(10));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("EGL device 99 (far-daemon --gpu) is not usable"), std::string::npos)
      << missing.out << missing.err;
}

}  // namespace
}  // namespace far::integration
