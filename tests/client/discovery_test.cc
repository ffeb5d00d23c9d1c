// far::client's way to a daemon it is not told the name of (far/client/discovery.h): the job's
// GPUs from the scheduler's variables, the ranking auto uses, $FAR_DAEMON, and what FindDaemons
// makes of sockets no daemon listens on. Real daemons: AutoDaemonTest (tests/integration).
#include "far/client/discovery.h"

#include <stdlib.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <gtest/gtest.h>

namespace far::client {
namespace {

// Sets environment variables for one test and restores them after.
class ScopedEnvironment {
 public:
  void Set(const std::string& name, const char* value) {
    if (!saved_.count(name)) {
      const char* old = getenv(name.c_str());
      saved_[name] = old ? std::optional<std::string>(old) : std::nullopt;
    }
    if (value) {
      setenv(name.c_str(), value, 1);
    } else {
      unsetenv(name.c_str());
    }
  }
  ~ScopedEnvironment() {
    for (const auto& [name, value] : saved_) {
      if (value) {
        setenv(name.c_str(), value->c_str(), 1);
      } else {
        unsetenv(name.c_str());
      }
    }
  }

 private:
  std::map<std::string, std::optional<std::string>> saved_;
};

const char* const kGpuVariables[] = {"FAR_GPUS", "SLURM_STEP_GPUS", "SLURM_JOB_GPUS",
                                     "NVIDIA_VISIBLE_DEVICES"};

TEST(JobGpusTest, TheFirstSchedulerVariableSetNamesTheGpus) {
  ScopedEnvironment env;
  for (const char* variable : kGpuVariables) env.Set(variable, nullptr);
  env.Set("CUDA_VISIBLE_DEVICES", "0");  // counts visible devices: never read
  EXPECT_TRUE(JobGpus().empty());
  env.Set("NVIDIA_VISIBLE_DEVICES", "GPU-aa,GPU-bb");
  EXPECT_EQ(JobGpus(), (std::vector<std::string>{"GPU-aa", "GPU-bb"}));
  env.Set("SLURM_JOB_GPUS", "0,1,2,3");
  EXPECT_EQ(JobGpus(), (std::vector<std::string>{"0", "1", "2", "3"}));
  env.Set("SLURM_STEP_GPUS", "2");
  EXPECT_EQ(JobGpus(), (std::vector<std::string>{"2"}));
  env.Set("FAR_GPUS", " 3 , ,1");
  EXPECT_EQ(JobGpus(), (std::vector<std::string>{"3", "1"}));
}

TEST(JobGpusTest, NvidiasAllNoneAndVoidNameNoParticularGpu) {
  ScopedEnvironment env;
  for (const char* variable : kGpuVariables) env.Set(variable, nullptr);
  for (const char* value : {"all", "none", "void", ""}) {
    env.Set("NVIDIA_VISIBLE_DEVICES", value);
    EXPECT_TRUE(JobGpus().empty()) << value;
  }
}

FoundDaemon Answered(const std::string& path, int sessions, std::vector<std::string> gpus) {
  DaemonStatus status;
  status.daemon_name = std::filesystem::path(path).stem();
  status.sessions_open = sessions;
  status.max_sessions = 64;
  status.gpu_names = std::move(gpus);
  return FoundDaemon{path, status, ""};
}

TEST(RankDaemonsTest, OnlyTheDaemonsOfTheJobsGpusLeastLoadedFirst) {
  const std::vector<FoundDaemon> found = {
      Answered("/run/far/gpu-0.sock", 3, {"0", "GPU-aa", "0000:3b:00.0"}),
      Answered("/run/far/gpu-1.sock", 1, {"1", "GPU-bb", "0000:5e:00.0"}),
      Answered("/run/far/gpu-2.sock", 0, {"2", "GPU-cc", "0000:86:00.0"}),
      FoundDaemon{"/run/far/dead.sock", std::nullopt, "connection refused"},
  };
  EXPECT_EQ(RankDaemons(found, {"1"}, 0), (std::vector<size_t>{1}));
  EXPECT_EQ(RankDaemons(found, {"GPU-AA", "1"}, 0), (std::vector<size_t>{1, 0}));
  EXPECT_EQ(RankDaemons(found, {"5e:00.0"}, 7), (std::vector<size_t>{1}));
  // No daemon serves the job's GPU, or the job names none: every daemon that answered, least
  // loaded first; the dead socket never.
  EXPECT_EQ(RankDaemons(found, {"7"}, 0), (std::vector<size_t>{2, 1, 0}));
  EXPECT_EQ(RankDaemons(found, {}, 0), (std::vector<size_t>{2, 1, 0}));
  EXPECT_TRUE(RankDaemons({found[3]}, {}, 0).empty());
}

TEST(RankDaemonsTest, EquallyLoadedDaemonsAreSpreadOverTheJobsProcesses) {
  const std::vector<FoundDaemon> found = {
      Answered("/run/far/a.sock", 2, {}), Answered("/run/far/b.sock", 2, {}),
      Answered("/run/far/c.sock", 2, {}), Answered("/run/far/d.sock", 5, {})};
  std::map<size_t, int> first;
  for (uint64_t pid = 1000; pid < 1030; ++pid) {
    const std::vector<size_t> ranked = RankDaemons(found, {}, pid);
    ASSERT_EQ(ranked.size(), 4u);
    EXPECT_EQ(ranked.back(), 3u) << "the most loaded stays last";
    EXPECT_EQ(std::set<size_t>(ranked.begin(), ranked.end()).size(), 4u);
    first[ranked.front()]++;
  }
  EXPECT_EQ(first, (std::map<size_t, int>{{0, 10}, {1, 10}, {2, 10}}));
}

TEST(DaemonEnvironmentTest, FarDaemonNamesTheDaemonOfOptionsThatNameNone) {
  ScopedEnvironment env;
  env.Set("FAR_DAEMON", nullptr);
  EXPECT_EQ(WithDaemonFromEnvironment({}).daemon, "far");
  env.Set("FAR_DAEMON", "auto");
  EXPECT_EQ(WithDaemonFromEnvironment({}).daemon, "auto");
  ClientOptions named;
  named.daemon = "gpu-1";
  EXPECT_EQ(WithDaemonFromEnvironment(named).daemon, "gpu-1") << "a name given wins";
  named.daemon = "far";
  EXPECT_EQ(WithDaemonFromEnvironment(named).daemon, "far") << "also the default's";
  ClientOptions by_socket;
  by_socket.socket_path = "/tmp/x/far.sock";
  EXPECT_EQ(WithDaemonFromEnvironment(by_socket).daemon, "far") << "a socket given wins";
}

TEST(FindDaemonsTest, SocketsNobodyListensOnAreListedWithWhyAndOtherFilesNot) {
  ScopedEnvironment env;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("far-discovery-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  env.Set("FAR_SOCKET_DIR", dir.c_str());
  // A socket left by a daemon that died: bound, then closed.
  const int fd = socket(AF_UNIX, SOCK_SEQPACKET, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string path = (dir / "dead.sock").string();
  std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", path.c_str());
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  close(fd);
  std::ofstream(dir / "file.sock") << "not a socket";
  std::ofstream(dir / "notes.txt") << "not a daemon";

  const std::vector<FoundDaemon> found = FindDaemons();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].socket_path, path);
  EXPECT_FALSE(found[0].status);
  EXPECT_FALSE(found[0].error.empty());

  ClientOptions automatic;
  automatic.daemon = "auto";
  automatic.connect_timeout = std::chrono::milliseconds(100);
  auto status = Client::Status(automatic);
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(status.error().message.find("no far-daemon answers"), std::string::npos)
      << status.error().message;
  EXPECT_NE(status.error().message.find(path), std::string::npos) << status.error().message;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace far::client
