#include "fair_shares.h"

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <vector>

#include "far/client/client.h"
#include "far/model/mesh.h"

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kCannotSwitchUser = 77;

// One vertex and every triangle (0, 0, 0): the cheapest mesh of that many triangles to send,
// check and build (no vertex budget to speak of).
Mesh DegenerateMesh(int64_t triangles) {
  Mesh mesh;
  mesh.p_MV = {Eigen::Vector3d::Zero()};
  mesh.triangles.assign(static_cast<size_t>(triangles), {0, 0, 0});
  return mesh;
}

// The cheapest step: it applies the session's updates and answers with the object PCS.
StepRequest DrainRequest() {
  StepRequest request;
  request.method = Method::kAabb;
  request.output = Output::kObjectPcs;
  return request;
}

// A line from the child ("" at its end of file).
std::string ReadLine(FILE* in) {
  std::string line;
  for (int c; (c = std::fgetc(in)) != EOF && c != '\n';) line.push_back(static_cast<char>(c));
  return line;
}

// Opens `sessions` sessions, each uploading one object of `triangles` triangles (stepped once,
// so that the daemon has applied it), and keeps those that worked in `held`.
HeldReport OpenAndUpload(const std::string& socket, int sessions, int64_t triangles,
                         std::vector<std::unique_ptr<client::Client>>* held) {
  HeldReport report;
  const Mesh mesh = triangles > 0 ? DegenerateMesh(triangles) : Mesh{};
  const auto start = Clock::now();
  for (int i = 0; i < sessions; ++i) {
    client::ClientOptions options;
    options.socket_path = socket;
    options.client_name = "held-" + std::to_string(getuid()) + "-" + std::to_string(i);
    options.timeout = std::chrono::seconds(120);
    auto client = client::Client::Connect(options);
    Result<void> ok = client ? Result<void>() : Result<void>(client.error());
    if (ok && triangles > 0) ok = (*client)->AddObject(1, mesh, Motion::kStatic);
    if (ok && triangles > 0) {
      auto stepped = (*client)->Step(DrainRequest());
      if (!stepped) ok = stepped.error();
    }
    if (!ok) {
      ++report.refused;
      if (report.refusal.empty()) report.refusal = far::ToString(ok.error());
      continue;
    }
    ++report.opened;
    report.triangles += triangles;
    held->push_back(std::move(*client));
  }
  report.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return report;
}

}  // namespace

std::string Millions(int64_t count) {
  if (count < 10'000) return std::to_string(count);
  char text[32];
  std::snprintf(text, sizeof(text), "%.1fM", count / 1e6);
  return text;
}

int HoldAsUserMain(const std::string& socket, int sessions, int64_t triangles) {
  std::vector<std::unique_ptr<client::Client>> held;
  const HeldReport report = OpenAndUpload(socket, sessions, triangles, &held);
  std::printf("held %d %d %lld %.6f\n%s\n", report.opened, report.refused,
              static_cast<long long>(report.triangles), report.seconds, report.refusal.c_str());
  std::fflush(stdout);
  // Idle until the parent lets go (its end of our stdin closes).
  char byte;
  while (read(STDIN_FILENO, &byte, 1) > 0) {
  }
  int alive = 0;
  std::string closed_because;
  for (auto& client : held) {
    auto stepped = client->Step(DrainRequest());
    if (stepped) {
      ++alive;
    } else if (closed_because.empty()) {
      closed_because = far::ToString(stepped.error());
    }
  }
  std::printf("after %d\n%s\n", alive, closed_because.c_str());
  std::fflush(stdout);
  return 0;
}

std::unique_ptr<HeldSessions> HeldSessions::Start(const std::string& self,
                                                  const std::string& socket, uid_t uid,
                                                  int sessions, int64_t triangles) {
  std::unique_ptr<HeldSessions> held(new HeldSessions());
  held->uid_ = uid;
  if (geteuid() != 0) {
    held->report_.not_run = "not root: no other uid to run as";
    return held;
  }
  std::vector<std::string> args = {self, kHoldAsUserFlag, socket, std::to_string(sessions),
                                   std::to_string(triangles)};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int in[2], out[2];
  if (pipe2(in, O_CLOEXEC) != 0 || pipe2(out, O_CLOEXEC) != 0) {
    held->report_.not_run = "pipe failed";
    return held;
  }
  held->pid_ = fork();
  if (held->pid_ == 0) {
    dup2(in[0], STDIN_FILENO);
    dup2(out[1], STDOUT_FILENO);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (setgroups(0, nullptr) != 0 || setresgid(uid, uid, uid) != 0 ||
        setresuid(uid, uid, uid) != 0) {
      _exit(kCannotSwitchUser);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(in[0]);
  close(out[1]);
  held->to_child_ = in[1];
  held->from_child_ = out[0];
  FILE* from = fdopen(dup(held->from_child_), "r");
  std::string word;
  const std::string line = from ? ReadLine(from) : "";
  HeldReport& r = held->report_;
  long long triangles_held = 0;
  if (std::sscanf(line.c_str(), "held %d %d %lld %lf", &r.opened, &r.refused, &triangles_held,
                  &r.seconds) != 4) {
    r.not_run = "the child (uid " + std::to_string(uid) + ") said \"" + line + "\"";
  } else {
    r.triangles = triangles_held;
    r.refusal = ReadLine(from);
  }
  if (from) std::fclose(from);
  return held;
}

void HeldSessions::Finish() {
  if (to_child_ < 0) return;
  close(to_child_);
  to_child_ = -1;
  FILE* from = fdopen(from_child_, "r");
  from_child_ = -1;
  if (from == nullptr) return;
  const std::string line = ReadLine(from);
  if (std::sscanf(line.c_str(), "after %d", &report_.alive_after) == 1)
    report_.closed_because = ReadLine(from);
  std::fclose(from);
}

HeldSessions::~HeldSessions() {
  if (to_child_ >= 0) close(to_child_);
  if (from_child_ >= 0) close(from_child_);
  if (pid_ > 0) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
}

}  // namespace far::study
