// LCM's udpm provider where its multicast group has no route: a network namespace of its own
// whose loopback is down (unshare -n, inside the test's namespace). LCM 1.3.1 freed its
// provider and then read the group's address from the freed memory to say which group had no
// route ("No route to 67.118.190.247", a different address each time; a heap use-after-free
// under ASan). far's LCM patch (hunk 12, docs/protocol.md) reads it first. The ci-asan stage of
// deploy/run-sanitizers.sh runs this test.
#include <filesystem>
#include <string>

#include "daemon_process.h"
#include <gtest/gtest.h>

namespace far::integration {
namespace {

using namespace std::chrono_literals;

constexpr const char* kUnshare = "/usr/bin/unshare";

// Not the default group: the message must name this one, not a constant it happens to hold.
constexpr const char* kGroup = "239.255.76.99";

TEST(LcmRouteErrorTest, ADaemonWithoutAMulticastRouteNamesItsGroupAndExits) {
  ASSERT_TRUE(std::filesystem::exists(kUnshare)) << kUnshare << " is missing (util-linux)";
  TempDir dir;
  const std::string url = std::string("udpm://") + kGroup + ":7668?ttl=0";
  const ProcessResult daemon = RunProcess({kUnshare, "-n", FAR_DAEMON_PATH, "--socket",
                                           (dir.path() / "far.sock").string(), "--lcm-url", url},
                                          30s);
  const std::string said = daemon.out + daemon.err;
  ASSERT_EQ(said.find("unshare failed"), std::string::npos)
      << "this test needs a network namespace of its own (root, or inside deploy/netns-run.sh "
         "as ctest runs it): "
      << said;
  EXPECT_EQ(said.find("AddressSanitizer"), std::string::npos) << said;
  EXPECT_EQ(daemon.exit_code, 1) << said;
  EXPECT_NE(said.find(std::string("No route to ") + kGroup + "\n"), std::string::npos) << said;
  EXPECT_NE(said.find("LCM cannot start on '" + url + "'"), std::string::npos) << said;
}

}  // namespace
}  // namespace far::integration
