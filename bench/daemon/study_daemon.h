#pragma once

// A far-daemon process for the hardening study: started with fork/exec (its output in a log
// file), its socket in a folder any user may enter (so that a client of another uid reaches
// it), stopped with SIGTERM (SIGKILL when it does not exit).

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "far/base/result.h"
#include "far/client/client.h"

namespace far::study {

/// Seconds on the steady clock since `start`.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class StudyDaemon {
 public:
  /// Starts `daemon_path` with `args` plus --socket and --log-level info, and waits (up to
  /// 15 s) until it answers a status request. Errors: kUnavailable with the log's tail.
  static Result<std::unique_ptr<StudyDaemon>> Start(const std::string& daemon_path,
                                                    const std::vector<std::string>& args);
  ~StudyDaemon();
  StudyDaemon(const StudyDaemon&) = delete;
  StudyDaemon& operator=(const StudyDaemon&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& socket_path() const { return socket_path_; }
  /// Client options for this daemon: its socket, a client name, a step timeout.
  client::ClientOptions Options(const std::string& name,
                                std::chrono::milliseconds timeout = std::chrono::seconds(60)) const;
  Result<client::DaemonStatus> Status() const;
  /// VmRSS of the process in KiB (-1 when it cannot be read).
  int64_t ResidentKiB() const { return StatusKiB("VmRSS"); }
  /// A size field of /proc/<pid>/status ("VmRSS", "RssAnon", "RssShmem", ...) in KiB, or -1.
  int64_t StatusKiB(const std::string& field) const;
  /// The resident size once no session is open any more and it stopped falling (session
  /// workers free their memory as they end).
  int64_t SettledResidentKiB() const;
  /// CPU time the process has used (user + system, all threads), in seconds.
  double CpuSeconds() const;
  /// The log file (the daemon's stdout and stderr) and its size in bytes.
  const std::filesystem::path& log_path() const { return log_path_; }
  int64_t LogBytes() const;
  /// True while the process runs.
  bool Running();

 private:
  StudyDaemon() = default;
  std::filesystem::path dir_, log_path_;
  std::string socket_path_;
  pid_t pid_ = -1;
  bool exited_ = false;
};

/// The CPU's model name from /proc/cpuinfo ("unknown CPU" when it has none).
std::string CpuModel();

/// Re-runs this program inside a private network namespace through `netns_run`
/// (deploy/netns-run.sh), as the integration tests run, unless it already runs in one
/// (FAR_IN_NETNS=1): LCM multicast then never leaves the machine. Returns only inside.
void EnterNetworkNamespace(int argc, char** argv, const char* netns_run);

}  // namespace far::study
