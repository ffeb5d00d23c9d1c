#pragma once

// Real processes for the integration tests: far-daemon started with fork/exec (its output in a
// log file that a failing test prints, its socket in a folder of its own), far-client runs with
// their output captured, and the session segments a daemon has mapped.
//
// Every test runs in its own network namespace (deploy/netns-run.sh, set as the test target's
// CROSSCOMPILING_EMULATOR), so the default udpm URL reaches only the processes of that test.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "far/base/result.h"
#include "far/client/client.h"

namespace far::integration {

/// The LCM URL every integration test uses: the default one, private to the test's namespace.
std::string TestLcmUrl();

/// A temporary folder, removed (with its contents) on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// One far-daemon process. Start() forks and execs FAR_DAEMON_PATH with `args` (plus
/// --lcm-url, --log-level, --gpu-cost-cache (the tree's FAR_TEST_GPU_COST_CACHE, shared by its
/// tests) and --socket <its folder>/far.sock unless given; with --name and no
/// --socket the daemon takes its default socket for that name), its stdout and
/// stderr in a log file, then waits until it answers a status request (Client::Status,
/// retried for up to `ready_timeout`). The most recently started daemon's socket is the one
/// TestClientOptions and RunFarClient use.
/// Stop() sends SIGTERM and waits (bounded) for the exit status. The destructor SIGKILLs a
/// process that is still running, so no test leaves one behind whatever fails.
class DaemonProcess {
 public:
  explicit DaemonProcess(std::vector<std::string> args = {});
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  /// Starts the process and waits until it answers. Errors: kUnavailable (fork/exec failed,
  /// the process exited, or it did not answer in time; the message holds the log's tail).
  Result<void> Start(std::chrono::milliseconds ready_timeout = std::chrono::seconds(30));
  /// SIGTERM, then waits up to `timeout` (then SIGKILL). Returns the exit code (128 + signal
  /// when killed by one), or an error when it was not running.
  Result<int> Stop(std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// SIGKILL and reap (the daemon gets no chance to clean up).
  void Kill();
  /// True while the process has not exited (reaps it when it has).
  bool Running();

  pid_t pid() const { return pid_; }
  /// Its socket (--socket).
  const std::string& socket_path() const { return socket_path_; }
  /// The whole log so far (stdout and stderr of the daemon).
  std::string Log() const;
  /// The log file's path.
  const std::filesystem::path& log_path() const { return log_path_; }

 private:
  std::vector<std::string> args_;
  TempDir dir_;
  std::filesystem::path log_path_;
  std::string socket_path_;
  pid_t pid_ = -1;
  int exit_status_ = -1;  // raw waitpid status once reaped
};

/// What a child process did.
struct ProcessResult {
  int exit_code = -1;  ///< exit status, or 128 + signal, or -1 when it could not run
  std::string out, err;
  bool timed_out = false;
};

/// Runs `argv` (argv[0] a path), waits up to `timeout` (then SIGKILL), and returns its exit
/// code and output.
ProcessResult RunProcess(const std::vector<std::string>& argv,
                         std::chrono::milliseconds timeout = std::chrono::seconds(60));

/// A child process whose stdout the test reads line by line (stderr goes to the test's).
/// The destructor SIGKILLs and reaps it if it is still running.
class ChildProcess {
 public:
  /// Forks and execs `argv` (argv[0] a path); with `user`, as that uid (and gid, with no
  /// supplementary groups: only root may), the child exiting with kCannotSwitchUser when it
  /// cannot switch. The other user may not reach argv[0] (a clone under a 0700 /root), so it
  /// runs a copy of it in a directory of its own under the temp directory (mode 0755, removed
  /// with *this*), from `/`. Errors: kUnavailable (also when that user cannot enter the temp
  /// directory: the message names the folder in the way). With `with_stderr`, its stderr is
  /// read as stdout too.
  static Result<std::unique_ptr<ChildProcess>> Spawn(const std::vector<std::string>& argv,
                                                     std::optional<uid_t> user = std::nullopt,
                                                     bool with_stderr = false);
  static constexpr int kCannotSwitchUser = 77;
  ~ChildProcess();
  /// The next line of its stdout (without the newline); nullopt at EOF or after `timeout`.
  std::optional<std::string> ReadLine(std::chrono::milliseconds timeout);
  /// Waits up to `timeout` for it to exit; returns its exit code (128 + signal), or nullopt.
  std::optional<int> Wait(std::chrono::milliseconds timeout);
  /// SIGKILL and reap; returns the exit code.
  int Kill();
  pid_t pid() const { return pid_; }

 private:
  ChildProcess() = default;
  pid_t pid_ = -1;
  int out_ = -1;
  std::string buffer_;
  std::optional<int> exit_code_;
  std::unique_ptr<TempDir> executable_dir_;  // the copy another user runs; outlives the child
};

/// The path of this test binary (/proc/self/exe).
std::string SelfPath();

/// The socket of the most recently started DaemonProcess ("" before any).
std::string CurrentSocketPath();

/// Runs FAR_CLIENT_PATH with `args` (and --socket CurrentSocketPath() unless `args` name a
/// socket or a daemon).
ProcessResult RunFarClient(const std::vector<std::string>& args,
                           std::chrono::milliseconds timeout = std::chrono::seconds(60));

/// The session segments ("far-session-<id>") the process `pid` has mapped (/proc/<pid>/maps).
std::vector<std::string> SessionSegmentsOf(pid_t pid);

/// The resident memory of process `pid` in KiB, or -1: `field` of /proc/<pid>/status, VmRSS
/// (all of it), RssAnon (private), RssShmem (shared memory: session segments) or RssFile.
int64_t ResidentKiB(pid_t pid, const std::string& field = "VmRSS");

/// Waits until `condition` holds, checking every 20 ms, up to `timeout`. Returns whether it held.
bool WaitUntil(const std::function<bool()>& condition, std::chrono::milliseconds timeout);

/// Client options for the tests: the current daemon's socket, a name, a step timeout.
client::ClientOptions TestClientOptions(
    const std::string& name, std::chrono::milliseconds timeout = std::chrono::seconds(5));

}  // namespace far::integration
