#include "study_daemon.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;

std::string Tail(const std::filesystem::path& path, size_t bytes = 4000) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string all = text.str();
  return all.size() > bytes ? all.substr(all.size() - bytes) : all;
}

}  // namespace

Result<std::unique_ptr<StudyDaemon>> StudyDaemon::Start(const std::string& daemon_path,
                                                        const std::vector<std::string>& args) {
  std::unique_ptr<StudyDaemon> daemon(new StudyDaemon());
  std::string dir = (std::filesystem::temp_directory_path() / "far-hardening-XXXXXX").string();
  if (mkdtemp(dir.data()) == nullptr)
    return MakeError(ErrorCode::kUnavailable, std::string("mkdtemp: ") + std::strerror(errno));
  // Any user may enter (not write): a second user's clients reach the socket.
  chmod(dir.c_str(), 0755);
  daemon->dir_ = dir;
  daemon->log_path_ = daemon->dir_ / "far-daemon.log";
  daemon->socket_path_ = (daemon->dir_ / "far.sock").string();
  std::vector<std::string> argv_strings = {daemon_path, "--socket", daemon->socket_path_,
                                           "--log-level", "info"};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int log = open(daemon->log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
  if (log < 0) return MakeError(ErrorCode::kUnavailable, "cannot open the daemon's log");
  daemon->pid_ = fork();
  if (daemon->pid_ == 0) {
    dup2(log, STDOUT_FILENO);
    dup2(log, STDERR_FILENO);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    syscall(SYS_close_range, 3u, ~0u, 0u);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(log);
  if (daemon->pid_ < 0) return MakeError(ErrorCode::kUnavailable, "fork failed");
  const auto deadline = Clock::now() + std::chrono::seconds(15);
  while (Clock::now() < deadline) {
    if (!daemon->Running()) break;
    client::ClientOptions options = daemon->Options("ready");
    options.connect_timeout = std::chrono::milliseconds(300);
    if (client::Client::Status(options)) return daemon;
  }
  return MakeError(ErrorCode::kUnavailable,
                   daemon_path + " did not start; its log:\n" + Tail(daemon->log_path_));
}

StudyDaemon::~StudyDaemon() {
  if (pid_ > 0 && Running()) {
    kill(pid_, SIGTERM);
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (Running() && Clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (Running()) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

bool StudyDaemon::Running() {
  if (pid_ <= 0 || exited_) return false;
  if (waitpid(pid_, nullptr, WNOHANG) == pid_) exited_ = true;
  return !exited_;
}

client::ClientOptions StudyDaemon::Options(const std::string& name,
                                           std::chrono::milliseconds timeout) const {
  client::ClientOptions options;
  options.socket_path = socket_path_;
  options.client_name = name;
  options.timeout = timeout;
  return options;
}

Result<client::DaemonStatus> StudyDaemon::Status() const {
  return client::Client::Status(Options("study-status"));
}

int64_t StudyDaemon::StatusKiB(const std::string& field) const {
  std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
  std::string line;
  const std::string key = field + ":";
  while (std::getline(status, line)) {
    if (line.rfind(key, 0) == 0) return std::strtoll(line.c_str() + key.size(), nullptr, 10);
  }
  return -1;
}

double StudyDaemon::CpuSeconds() const {
  std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  if (text.empty()) return -1;
  // After "(comm)": state is field 3; utime and stime are fields 14 and 15, in clock ticks.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  for (int i = 3; i < 14; ++i) fields >> field;
  long long utime = 0, stime = 0;
  fields >> utime >> stime;
  return static_cast<double>(utime + stime) / sysconf(_SC_CLK_TCK);
}

int64_t StudyDaemon::SettledResidentKiB() const {
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (Clock::now() < deadline) {
    auto status = Status();
    if (status && status->sessions_open == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  int64_t last = ResidentKiB();
  for (int i = 0; i < 15; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const int64_t now = ResidentKiB();
    if (now > last - 256) return now;
    last = now;
  }
  return last;
}

int64_t StudyDaemon::LogBytes() const {
  std::error_code ec;
  const auto size = std::filesystem::file_size(log_path_, ec);
  return ec ? -1 : static_cast<int64_t>(size);
}

std::string CpuModel() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

void EnterNetworkNamespace(int argc, char** argv, const char* netns_run) {
  const char* in = std::getenv("FAR_IN_NETNS");
  if (in != nullptr && std::strcmp(in, "1") == 0) return;
  std::vector<char*> args = {const_cast<char*>(netns_run)};
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  args.push_back(const_cast<char*>(self.c_str()));
  for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(netns_run, args.data());
  std::fprintf(stderr, "%s: cannot run %s\n", self.c_str(), netns_run);
  std::exit(1);
}

}  // namespace far::study
