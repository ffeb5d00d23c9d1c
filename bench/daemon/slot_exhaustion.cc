#include "slot_exhaustion.h"

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <sstream>

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;

constexpr uid_t kOtherUid = 65534;
constexpr int kCannotSwitchUser = 77;

OpenReport OpenMany(const client::ClientOptions& options, int attempts,
                    std::vector<std::unique_ptr<client::Client>>* held) {
  OpenReport report;
  const auto start = Clock::now();
  for (int i = 0; i < attempts; ++i) {
    ++report.attempts;
    auto client = client::Client::Connect(options);
    if (client) {
      ++report.opened;
      held->push_back(std::move(*client));
    } else {
      ++report.refused;
      if (report.refusal.empty()) report.refusal = far::ToString(client.error());
    }
  }
  report.seconds = SecondsSince(start);
  return report;
}

// Reads the child's whole output.
std::string ReadAll(int fd) {
  std::string text;
  char buffer[4096];
  ssize_t n;
  while ((n = read(fd, buffer, sizeof(buffer))) > 0) text.append(buffer, static_cast<size_t>(n));
  return text;
}

}  // namespace

OpenReport OpenAsFastAsPossible(const StudyDaemon& daemon, int attempts,
                                std::vector<std::unique_ptr<client::Client>>* held) {
  return OpenMany(daemon.Options("hog"), attempts, held);
}

int OtherUserMain(const std::string& socket, int attempts) {
  client::ClientOptions options;
  options.socket_path = socket;
  options.client_name = "other-user";
  std::vector<std::unique_ptr<client::Client>> held;
  const OpenReport report = OpenMany(options, attempts, &held);
  std::printf("opened %d refused %d %.6f\n%s\n", report.opened, report.refused, report.seconds,
              report.refusal.c_str());
  return 0;
}

OpenReport OpenAsOtherUser(const std::string& self, const std::string& socket, int attempts) {
  OpenReport report;
  if (geteuid() != 0) {
    report.not_run = "not root: no second uid to run as";
    return report;
  }
  std::vector<std::string> args = {self, kOtherUserFlag, socket, std::to_string(attempts)};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int out[2];
  if (pipe2(out, O_CLOEXEC) != 0) {
    report.not_run = "pipe failed";
    return report;
  }
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (setgroups(0, nullptr) != 0 || setresgid(kOtherUid, kOtherUid, kOtherUid) != 0 ||
        setresuid(kOtherUid, kOtherUid, kOtherUid) != 0) {
      _exit(kCannotSwitchUser);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(out[1]);
  const std::string text = ReadAll(out[0]);
  close(out[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    report.not_run = WIFEXITED(status) && WEXITSTATUS(status) == kCannotSwitchUser
                         ? "cannot switch to uid 65534"
                         : "the child failed: " + text;
    return report;
  }
  std::istringstream in(text);
  std::string word;
  in >> word >> report.opened >> word >> report.refused >> report.seconds;
  std::getline(in, word);
  std::getline(in, report.refusal);
  report.attempts = attempts;
  return report;
}

}  // namespace far::study
