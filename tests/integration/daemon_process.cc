#include "daemon_process.h"

#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "far/protocol/channels.h"

namespace far::integration {
namespace {

using Clock = std::chrono::steady_clock;

// In a freshly forked child (async-signal-safe calls only): die with the test process, close
// every inherited descriptor above stderr (the test's LCM sockets), then exec.
[[noreturn]] void ExecChild(const std::vector<char*>& argv) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  syscall(SYS_close_range, 3u, ~0u, 0u);
  execv(argv[0], argv.data());
  _exit(127);
}

std::vector<char*> CArgs(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return argv;
}

int DecodeStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

bool HasFlag(const std::vector<std::string>& args, const std::string& flag) {
  for (const auto& a : args) {
    if (a == flag || a.rfind(flag + "=", 0) == 0) return true;
  }
  return false;
}

// The value of "--flag value" in args, or "".
std::string FlagValue(const std::vector<std::string>& args, const std::string& flag) {
  for (size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == flag) return args[i + 1];
  }
  return "";
}

std::string g_current_socket;

}  // namespace

std::string CurrentSocketPath() { return g_current_socket; }

std::string TestLcmUrl() { return std::string(protocol::kDefaultLcmUrl); }

TempDir::TempDir() {
  std::string templ = (std::filesystem::temp_directory_path() / "far-integration-XXXXXX").string();
  if (mkdtemp(templ.data()) == nullptr) {
    std::fprintf(stderr, "far_integration_test: mkdtemp failed: %s\n", std::strerror(errno));
    std::abort();
  }
  path_ = templ;
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

DaemonProcess::DaemonProcess(std::vector<std::string> args) : args_(std::move(args)) {
  log_path_ = dir_.path() / "far-daemon.log";
  socket_path_ = FlagValue(args_, "--socket");
  // Given a name and no socket, the daemon picks its socket by name, as clients find it.
  if (socket_path_.empty() && HasFlag(args_, "--name"))
    socket_path_ = protocol::DefaultSocketPath(FlagValue(args_, "--name"));
  if (socket_path_.empty()) socket_path_ = (dir_.path() / "far.sock").string();
}

DaemonProcess::~DaemonProcess() {
  if (pid_ > 0 && exit_status_ < 0) Kill();
}

Result<void> DaemonProcess::Start(std::chrono::milliseconds ready_timeout) {
  if (pid_ > 0 && exit_status_ < 0)
    return MakeError(ErrorCode::kInvalidArgument, "already running");
  std::vector<std::string> args = {FAR_DAEMON_PATH};
  if (!HasFlag(args_, "--lcm-url")) args.insert(args.end(), {"--lcm-url", TestLcmUrl()});
  if (!HasFlag(args_, "--log-level")) args.insert(args.end(), {"--log-level", "info"});
  // One cost cache for the tree's tests: the first daemon measures auto's GPU cost, the rest
  // start without the probe's seconds of rendering (docs/testing.md).
  if (!HasFlag(args_, "--gpu-cost-cache"))
    args.insert(args.end(), {"--gpu-cost-cache", FAR_TEST_GPU_COST_CACHE});
  if (!HasFlag(args_, "--socket") && !HasFlag(args_, "--name"))
    args.insert(args.end(), {"--socket", socket_path_});
  args.insert(args.end(), args_.begin(), args_.end());
  std::vector<char*> argv = CArgs(args);
  // Everything the child needs is prepared before fork: it only dup2s and execs.
  const int log = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
  if (log < 0) return MakeError(ErrorCode::kUnavailable, "cannot open " + log_path_.string());
  exit_status_ = -1;
  pid_ = fork();
  if (pid_ == 0) {
    dup2(log, STDOUT_FILENO);
    dup2(log, STDERR_FILENO);
    ExecChild(argv);
  }
  close(log);
  if (pid_ < 0)
    return MakeError(ErrorCode::kUnavailable, std::string("fork: ") + std::strerror(errno));

  // Ready when it answers a status request.
  g_current_socket = socket_path_;
  client::ClientOptions options;
  options.socket_path = socket_path_;
  options.connect_timeout = std::chrono::milliseconds(300);
  const auto deadline = Clock::now() + ready_timeout;
  while (Clock::now() < deadline) {
    if (!Running()) {
      return MakeError(ErrorCode::kUnavailable, "far-daemon exited with " +
                                                    std::to_string(DecodeStatus(exit_status_)) +
                                                    " during start-up; log:\n" + Log());
    }
    auto status = client::Client::Status(options);
    if (status) return {};
  }
  return MakeError(ErrorCode::kUnavailable, "far-daemon did not answer within " +
                                                std::to_string(ready_timeout.count()) +
                                                " ms; log:\n" + Log());
}

bool DaemonProcess::Running() {
  if (pid_ <= 0 || exit_status_ >= 0) return false;
  int status = 0;
  const pid_t done = waitpid(pid_, &status, WNOHANG);
  if (done == pid_) {
    exit_status_ = status;
    return false;
  }
  return done == 0;
}

Result<int> DaemonProcess::Stop(std::chrono::milliseconds timeout) {
  if (!Running()) {
    if (exit_status_ >= 0) {
      return MakeError(ErrorCode::kUnavailable, "far-daemon had already exited with " +
                                                    std::to_string(DecodeStatus(exit_status_)));
    }
    return MakeError(ErrorCode::kUnavailable, "far-daemon was not started");
  }
  kill(pid_, SIGTERM);
  if (!WaitUntil([&] { return !Running(); }, timeout)) {
    Kill();
    return MakeError(ErrorCode::kTimeout, "far-daemon did not exit within " +
                                              std::to_string(timeout.count()) + " ms of SIGTERM");
  }
  return DecodeStatus(exit_status_);
}

void DaemonProcess::Kill() {
  if (pid_ <= 0 || exit_status_ >= 0) return;
  kill(pid_, SIGKILL);
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  exit_status_ = status;
}

std::string DaemonProcess::Log() const {
  std::ifstream in(log_path_);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

ProcessResult RunProcess(const std::vector<std::string>& argv_in,
                         std::chrono::milliseconds timeout) {
  ProcessResult result;
  std::vector<std::string> args = argv_in;
  std::vector<char*> argv = CArgs(args);
  int out[2], err[2];
  if (pipe2(out, O_CLOEXEC) != 0) return result;
  if (pipe2(err, O_CLOEXEC) != 0) {
    close(out[0]);
    close(out[1]);
    return result;
  }
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    dup2(err[1], STDERR_FILENO);
    ExecChild(argv);
  }
  close(out[1]);
  close(err[1]);
  if (pid < 0) {
    close(out[0]);
    close(err[0]);
    return result;
  }
  // Read both pipes until they close or the time is up.
  const auto deadline = Clock::now() + timeout;
  pollfd fds[2] = {{out[0], POLLIN, 0}, {err[0], POLLIN, 0}};
  std::string* sinks[2] = {&result.out, &result.err};
  int open_pipes = 2;
  while (open_pipes > 0) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      result.timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    if (poll(fds, 2, static_cast<int>(std::min<int64_t>(left, 200))) < 0 && errno != EINTR) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      char buffer[65536];
      const ssize_t n = read(fds[i].fd, buffer, sizeof(buffer));
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_pipes;
      }
    }
  }
  for (auto& fd : fds) {
    if (fd.fd >= 0) close(fd.fd);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = DecodeStatus(status);
  return result;
}

namespace {

// A copy of `executable` that any user may run, in a fresh directory of `dir` (mode 0755), or
// an error naming the folder on the way that others cannot enter.
Result<std::string> CopyForAnyUser(const std::string& executable, const TempDir& dir) {
  for (std::filesystem::path p = dir.path().parent_path();; p = p.parent_path()) {
    struct stat st {};
    if (stat(p.c_str(), &st) != 0 || (st.st_mode & S_IXOTH) == 0) {
      char mode[8];
      std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(st.st_mode & 07777));
      return MakeError(ErrorCode::kUnavailable, "another user cannot enter " + p.string() +
                                                    " (mode " + mode +
                                                    "); set TMPDIR to a folder others may enter");
    }
    if (p == p.parent_path()) break;
  }
  std::error_code error;
  const auto copy = dir.path() / std::filesystem::path(executable).filename();
  if (chmod(dir.path().c_str(), 0755) != 0 ||
      !std::filesystem::copy_file(executable, copy, error) || chmod(copy.c_str(), 0755) != 0) {
    return MakeError(ErrorCode::kUnavailable, "copying " + executable + " to " + copy.string() +
                                                  " failed: " + error.message());
  }
  return copy.string();
}

}  // namespace

Result<std::unique_ptr<ChildProcess>> ChildProcess::Spawn(const std::vector<std::string>& argv_in,
                                                          std::optional<uid_t> user,
                                                          bool with_stderr) {
  std::vector<std::string> args = argv_in;
  std::unique_ptr<TempDir> executable_dir;
  if (user) {
    executable_dir = std::make_unique<TempDir>();
    auto copy = CopyForAnyUser(args.at(0), *executable_dir);
    if (!copy) return copy.error();
    args[0] = *copy;
  }
  std::vector<char*> argv = CArgs(args);
  int out[2];
  if (pipe2(out, O_CLOEXEC) != 0) return MakeError(ErrorCode::kUnavailable, "pipe failed");
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    if (with_stderr) dup2(out[1], STDERR_FILENO);
    // The child has one thread: these are plain system calls here. Group first (after the uid
    // changes, the child may no longer change it).
    if (user && (setgroups(0, nullptr) != 0 || setresgid(*user, *user, *user) != 0 ||
                 setresuid(*user, *user, *user) != 0)) {
      _exit(kCannotSwitchUser);
    }
    // The test's working directory may be one the other user cannot enter.
    if (user && chdir("/") != 0) _exit(kCannotSwitchUser);
    ExecChild(argv);
  }
  close(out[1]);
  if (pid < 0) {
    close(out[0]);
    return MakeError(ErrorCode::kUnavailable, std::string("fork: ") + std::strerror(errno));
  }
  std::unique_ptr<ChildProcess> child(new ChildProcess());
  child->pid_ = pid;
  child->out_ = out[0];
  child->executable_dir_ = std::move(executable_dir);
  return child;
}

ChildProcess::~ChildProcess() {
  if (!exit_code_) Kill();
  if (out_ >= 0) close(out_);
}

std::optional<std::string> ChildProcess::ReadLine(std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (true) {
    if (const size_t end = buffer_.find('\n'); end != std::string::npos) {
      std::string line = buffer_.substr(0, end);
      buffer_.erase(0, end + 1);
      return line;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0 || out_ < 0) return std::nullopt;
    pollfd fd{out_, POLLIN, 0};
    if (poll(&fd, 1, static_cast<int>(left)) <= 0) continue;
    char chunk[4096];
    const ssize_t n = read(out_, chunk, sizeof(chunk));
    if (n > 0) {
      buffer_.append(chunk, static_cast<size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      close(out_);
      out_ = -1;
    }
  }
}

std::optional<int> ChildProcess::Wait(std::chrono::milliseconds timeout) {
  if (exit_code_) return exit_code_;
  WaitUntil(
      [&] {
        int status = 0;
        if (waitpid(pid_, &status, WNOHANG) == pid_) exit_code_ = DecodeStatus(status);
        return exit_code_.has_value();
      },
      timeout);
  return exit_code_;
}

int ChildProcess::Kill() {
  if (exit_code_) return *exit_code_;
  kill(pid_, SIGKILL);
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  exit_code_ = DecodeStatus(status);
  return *exit_code_;
}

std::string SelfPath() { return std::filesystem::read_symlink("/proc/self/exe").string(); }

ProcessResult RunFarClient(const std::vector<std::string>& args,
                           std::chrono::milliseconds timeout) {
  std::vector<std::string> argv = {FAR_CLIENT_PATH};
  if (!HasFlag(args, "--socket") && !HasFlag(args, "--daemon"))
    argv.insert(argv.end(), {"--socket", CurrentSocketPath()});
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProcess(argv, timeout);
}

std::vector<std::string> SessionSegmentsOf(pid_t pid) {
  std::ifstream maps("/proc/" + std::to_string(pid) + "/maps");
  std::vector<std::string> names;
  std::string line;
  while (std::getline(maps, line)) {
    const size_t at = line.find("/memfd:far-session-");
    if (at == std::string::npos) continue;
    std::string name = line.substr(at + 7);  // after "/memfd:"
    name = name.substr(0, name.find(' '));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

int64_t ResidentKiB(pid_t pid, const std::string& field) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(field + ":", 0) == 0)
      return std::strtoll(line.c_str() + field.size() + 1, nullptr, 10);
  }
  return -1;
}

bool WaitUntil(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (true) {
    if (condition()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

client::ClientOptions TestClientOptions(const std::string& name,
                                        std::chrono::milliseconds timeout) {
  client::ClientOptions options;
  options.socket_path = CurrentSocketPath();
  options.client_name = name;
  options.timeout = timeout;
  return options;
}

}  // namespace far::integration
