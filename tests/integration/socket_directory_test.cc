// The per-user socket directory cannot be taken by another user (issue 41): a user whose
// /tmp/far-<uid> another uid made first used to have a daemon that would not start. Now the
// daemon and its clients move to $HOME/.far/run-<host> (protocol::PerUserSocketDirectory), and
// stay there even after the other user removes theirs; without a home of its own the daemon
// refuses to start, naming the owner and what to do. Played with three uids: the user (65534,
// or 65533 in the second suite: ctest runs tests side by side and /tmp is shared, so each
// suite has a /tmp/far-<uid> of its own; run as far-daemon and far-client), another uid that
// takes its directory (4242, by chown), and this test as root.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "daemon_process.h"
#include <gtest/gtest.h>

namespace far::integration {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

constexpr uid_t kSquatter = 4242;  // another uid, who made /tmp/far-65534 first

// Sets (or, with nullopt, unsets) an environment variable until destroyed.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, std::optional<std::string> value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      setenv(name, value->c_str(), 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// What a child printed (stdout and stderr) until it exited, and its exit code.
struct CommandOutput {
  std::string text;
  std::optional<int> exit_code;
};
CommandOutput RunAsUser(uid_t user, const std::vector<std::string>& argv,
                        std::chrono::seconds timeout = 30s) {
  CommandOutput output;
  auto child = ChildProcess::Spawn(argv, user, /*with_stderr=*/true);
  if (!child) {
    output.text = far::ToString(child.error());
    return output;
  }
  while (auto line = (*child)->ReadLine(timeout)) output.text += *line + "\n";
  output.exit_code = (*child)->Wait(5s);
  return output;
}

// `user`: the uid whose daemon and clients the test runs.
class SocketDirectoryFixture : public ::testing::Test {
 protected:
  explicit SocketDirectoryFixture(uid_t user) : user_(user) {}
  void SetUp() override {
    ASSERT_EQ(geteuid(), 0u) << "this test plays three users: it needs root";
    ASSERT_FALSE(fs::exists("/run/far")) << "/run/far exists: every default socket is there";
    ASSERT_FALSE(fs::exists(tmp_, ignored_))
        << tmp_ << " exists already (a daemon of uid " << user_ << "?): remove it to run this";
    // The other user's directory, made first.
    ASSERT_EQ(mkdir(tmp_.c_str(), 0755), 0);
    ASSERT_EQ(chown(tmp_.c_str(), kSquatter, kSquatter), 0);
    // The user's home: a directory of its own that it can reach.
    ASSERT_EQ(chmod(home_parent_.path().c_str(), 0755), 0);
    ASSERT_EQ(mkdir(home_.c_str(), 0700), 0);
    ASSERT_EQ(chown(home_.c_str(), user_, user_), 0);
  }
  void TearDown() override { fs::remove_all(tmp_, ignored_); }

  std::vector<std::string> DaemonArgs() const {
    return {FAR_DAEMON_PATH, "--lcm-url", TestLcmUrl(), "--log-level", "info"};
  }

  const uid_t user_;
  std::error_code ignored_;
  const std::string tmp_ = "/tmp/far-" + std::to_string(user_);
  TempDir home_parent_;
  const std::string home_ = (home_parent_.path() / "home").string();
  ScopedEnv no_dir_{"FAR_SOCKET_DIR", std::nullopt};
  ScopedEnv no_runtime_{"XDG_RUNTIME_DIR", std::nullopt};
};

class SocketDirectoryTest : public SocketDirectoryFixture {
 protected:
  SocketDirectoryTest() : SocketDirectoryFixture(65534) {}  // Debian's nobody
};

class SocketDirectoryNoHomeTest : public SocketDirectoryFixture {
 protected:
  SocketDirectoryNoHomeTest() : SocketDirectoryFixture(65533) {}
};

TEST_F(SocketDirectoryTest, AUserWhoseTmpDirectoryIsTakenServesFromItsHomeAndItsClientsFindIt) {
  ScopedEnv home("HOME", home_);
  auto daemon = ChildProcess::Spawn(DaemonArgs(), user_, /*with_stderr=*/true);
  ASSERT_TRUE(daemon.ok()) << far::ToString(daemon.error());
  std::string log;
  while (auto line = (*daemon)->ReadLine(30s)) {
    log += *line + "\n";
    if (line->find("event=daemon_ready") != std::string::npos) break;
  }
  ASSERT_NE(log.find("event=daemon_ready"), std::string::npos) << log;
  EXPECT_NE(log.find("event=socket_directory_taken reason=\"" + tmp_ + " belongs to uid " +
                     std::to_string(kSquatter) + "\""),
            std::string::npos)
      << log;
  const std::string socket_dir = home_ + "/.far/run-";
  EXPECT_NE(log.find("socket=" + socket_dir), std::string::npos) << log;

  // Its clients look where it listens, also once the other user removed theirs.
  CommandOutput status = RunAsUser(user_, {FAR_CLIENT_PATH, "status"});
  EXPECT_EQ(status.exit_code, 0) << status.text;
  EXPECT_NE(status.text.find("socket " + socket_dir), std::string::npos) << status.text;
  ASSERT_EQ(rmdir(tmp_.c_str()), 0);
  status = RunAsUser(user_, {FAR_CLIENT_PATH, "status"});
  EXPECT_EQ(status.exit_code, 0) << status.text;
  EXPECT_NE(status.text.find("socket " + socket_dir), std::string::npos) << status.text;
}

TEST_F(SocketDirectoryNoHomeTest, WithoutAHomeOfItsOwnTheDaemonRefusesNamingTheOwnerAndWhatToDo) {
  ScopedEnv home("HOME", "/nonexistent");
  const CommandOutput daemon = RunAsUser(user_, DaemonArgs());
  EXPECT_EQ(daemon.exit_code, 1) << daemon.text;
  for (const std::string& part :
       {"socket directory " + tmp_ + " (owner uid " + std::to_string(kSquatter),
        std::string("another user's directory: ask root to remove it"), std::string("--socket")}) {
    EXPECT_NE(daemon.text.find(part), std::string::npos) << part << "\n" << daemon.text;
  }
}

}  // namespace
}  // namespace far::integration
