#include "memory_attacks.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "large_scene.h"

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message.h"
#include "far/protocol/version.h"

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

int SessionsOpen(const StudyDaemon& daemon) {
  auto status = daemon.Status();
  return status ? status->sessions_open : -1;
}

// One open on the daemon's socket: the segment's descriptor (the connection closes as this
// returns, which closes the session), or the daemon's wire status when it refused.
struct OpenAnswer {
  int fd = -1;
  int32_t status = -1;
  std::string message;
};

OpenAnswer OpenAndLeave(const std::string& socket, int64_t request_id) {
  OpenAnswer answer;
  auto connection = protocol::LocalConnection::Connect(socket);
  if (!connection) {
    answer.message = far::ToString(connection.error());
    return answer;
  }
  far_lcm::open_session_t open{};
  open.protocol_version = protocol::kProtocolVersion;
  open.request_id = request_id;
  open.client_name = "hoarder";
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes || !connection->Send(*bytes)) {
    answer.message = "cannot send the open request";
    return answer;
  }
  auto reply = connection->Receive(protocol::kMaxControlMessageBytes, 5s, /*accept_fd=*/true);
  if (!reply) {
    answer.message = far::ToString(reply.error());
    return answer;
  }
  auto decoded = protocol::DecodeMessage<far_lcm::open_session_reply_t>(
      reply->bytes.data(), reply->bytes.size(), protocol::kMaxControlMessageBytes);
  answer.fd = reply->fd;
  answer.status = decoded ? decoded->status : -1;
  answer.message = decoded ? decoded->message : far::ToString(decoded.error());
  return answer;
}

// Waits until `done` holds, up to `timeout`.
template <typename Condition>
bool WaitFor(Condition done, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return done();
}

}  // namespace

int64_t MemInfoKiB(const std::string& field) {
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  const std::string key = field + ":";
  while (std::getline(meminfo, line)) {
    if (line.rfind(key, 0) == 0) return std::strtoll(line.c_str() + key.size(), nullptr, 10);
  }
  return -1;
}

FileBytes BytesOf(int fd) {
  struct stat info {};
  if (fstat(fd, &info) != 0) return {-1, -1};
  return {static_cast<int64_t>(info.st_blocks) * 512, static_cast<int64_t>(info.st_size)};
}

MappedSegment SegmentOf(pid_t pid, const std::string& name) {
  MappedSegment segment;
  std::ifstream maps("/proc/" + std::to_string(pid) + "/maps");
  std::string line;
  const std::string tag = "/memfd:" + name + " ";
  while (std::getline(maps, line)) {
    if (line.find(tag) == std::string::npos && !line.ends_with("/memfd:" + name)) continue;
    segment.mapped = true;
    const std::string range = line.substr(0, line.find(' '));
    const std::string file = "/proc/" + std::to_string(pid) + "/map_files/" + range;
    const int fd = open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      segment.allocated = BytesOf(fd).allocated;
      close(fd);
    }
    break;
  }
  return segment;
}

HoardReport HoardSegments(const StudyDaemon& daemon, int sessions) {
  HoardReport report;
  report.rss_before = daemon.ResidentKiB();
  report.shmem_before = MemInfoKiB("Shmem");
  std::vector<int> kept;
  const auto start = Clock::now();
  for (int64_t request = 1; report.opened < sessions && SecondsSince(start) < 60; ++request) {
    const OpenAnswer answer = OpenAndLeave(daemon.socket_path(), request);
    if (answer.fd >= 0) kept.push_back(answer.fd);
    if (answer.status == protocol::kWireOk && answer.fd >= 0) {
      ++report.opened;
    } else if (answer.status == protocol::ToWireStatus(ErrorCode::kBusy) ||
               answer.status == protocol::ToWireStatus(ErrorCode::kLimitExceeded)) {
      ++report.refusals;  // the open rate or the session limit: wait and try again
      std::this_thread::sleep_for(50ms);
    } else {
      report.error = "open " + std::to_string(request) + ": " + answer.message;
      break;
    }
  }
  WaitFor([&] { return SessionsOpen(daemon) == 0; }, 10s);
  report.seconds = SecondsSince(start);
  std::this_thread::sleep_for(1s);  // what is freed at close has been freed
  report.sessions_open = SessionsOpen(daemon);
  for (const int fd : kept) {
    const FileBytes bytes = BytesOf(fd);
    report.kept.allocated += bytes.allocated;
    report.kept.size += bytes.size;
  }
  report.rss_after = daemon.ResidentKiB();
  report.shmem_after = MemInfoKiB("Shmem");
  for (const int fd : kept) close(fd);
  std::this_thread::sleep_for(500ms);
  report.shmem_released = MemInfoKiB("Shmem");
  return report;
}

namespace {

// A child process with its stdout on a pipe, read line by line.
struct Child {
  pid_t pid = -1;
  FILE* out = nullptr;
  ~Child() {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    if (out != nullptr) fclose(out);
  }
  std::string ReadLine() {
    char line[512];
    if (out == nullptr || std::fgets(line, sizeof(line), out) == nullptr) return "";
    std::string text = line;
    if (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
  }
};

bool Spawn(const std::vector<std::string>& args, Child* child) {
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) return false;
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  child->pid = fork();
  if (child->pid == 0) {
    dup2(pipe_fds[1], STDOUT_FILENO);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(pipe_fds[1]);
  child->out = fdopen(pipe_fds[0], "r");
  return child->pid > 0;
}

// Watches the killed client's segment in the daemon until it is unmapped (or `watch_s`).
void WatchSegment(const StudyDaemon& daemon, double watch_s, KilledClientReport* report) {
  const auto killed = Clock::now();
  while (SecondsSince(killed) < watch_s) {
    const MappedSegment now = SegmentOf(daemon.pid(), report->segment);
    const double t = SecondsSince(killed);
    if (report->freed_after_s < 0 && (!now.mapped || now.allocated == 0)) report->freed_after_s = t;
    if (!now.mapped) {
      report->unmapped_after_s = t;
      report->rss_after = daemon.ResidentKiB();
      break;
    }
    std::this_thread::sleep_for(10ms);
  }
}

}  // namespace

namespace {

// Starts a child client in kKilledClientFlag mode and waits until its step was sent.
bool StartStepping(const StudyDaemon& daemon, const std::string& self, int64_t triangles,
                   const KilledClientSetup& setup, Child* child, int64_t* session_id) {
  if (!Spawn({self, kKilledClientFlag, daemon.socket_path(), std::to_string(triangles),
              setup.method, std::to_string(setup.resolution)},
             child)) {
    return false;
  }
  std::istringstream first(child->ReadLine());
  std::string segment;
  first >> *session_id >> segment;
  return *session_id > 0 && child->ReadLine() == "stepping";
}

}  // namespace

KilledClientReport KillClientMidStep(const StudyDaemon& daemon, const std::string& self,
                                     const KilledClientSetup& setup) {
  KilledClientReport report;
  Child neighbour, victim;
  int64_t neighbour_id = 0;
  if (setup.neighbour_triangles > 0 &&
      !StartStepping(daemon, self, setup.neighbour_triangles, setup, &neighbour, &neighbour_id)) {
    report.error = "the neighbour client did not open its session and step";
    return report;
  }
  if (!StartStepping(daemon, self, setup.triangles, setup, &victim, &report.session_id)) {
    report.error = "the client did not open its session and step";
    return report;
  }
  report.segment = "far-session-" + std::to_string(report.session_id);
  const auto stepping = Clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(setup.kill_after_s));
  report.allocated_at_kill = SegmentOf(daemon.pid(), report.segment).allocated;
  report.rss_at_kill = daemon.ResidentKiB();
  report.step_seconds_before_kill = SecondsSince(stepping);
  kill(victim.pid, SIGKILL);
  waitpid(victim.pid, nullptr, 0);
  victim.pid = -1;
  WatchSegment(daemon, setup.watch_s, &report);
  return report;
}

int KilledClientMain(int argc, char** argv) {
  if (argc != 6) return 2;
  client::ClientOptions options;
  options.socket_path = argv[2];
  options.client_name = "to-be-killed";
  options.timeout = std::chrono::seconds(600);
  auto client = client::Client::Connect(options);
  if (!client) return 3;
  const Scene scene = LargestScene(std::atoll(argv[3]));
  if (!UploadInParts(**client, scene)) return 4;
  std::printf("%lld far-session-%lld\nstepping\n", static_cast<long long>((*client)->session_id()),
              static_cast<long long>((*client)->session_id()));
  std::fflush(stdout);
  StepRequest request;
  request.method = ParseMethod(argv[4]).value_or(Method::kFar);
  request.resolution = std::atoi(argv[5]);
  request.output = Output::kContacts;
  (void)(*client)->Step(request);
  return 0;
}

BigFloodReport FloodLargeDatagrams(const StudyDaemon& daemon, int64_t bytes, double seconds,
                                   double settle_s) {
  BigFloodReport report;
  report.bytes = bytes;
  auto status = daemon.Status();
  if (!status) {
    report.error = far::ToString(status.error());
    return report;
  }
  auto bus = protocol::LcmBus::Create(status->lcm_url);
  if (!bus) {
    report.error = far::ToString(bus.error());
    return report;
  }
  report.rss_before = daemon.ResidentKiB();
  report.anon_before = daemon.StatusKiB("RssAnon");
  std::mt19937_64 random(41);
  std::vector<uint8_t> payload(static_cast<size_t>(bytes));
  for (auto& b : payload) b = static_cast<uint8_t>(random());
  const auto start = Clock::now();
  for (int64_t i = 0; SecondsSince(start) < seconds; ++i) {
    // Session channels 1..100, the daemon's subscription: every one is received and queued.
    const std::string channel =
        protocol::SessionRequestChannel(status->channel_prefix, 1 + i % 100);
    if ((*bus)->Publish(channel, payload)) ++report.sent;
  }
  report.seconds = SecondsSince(start);
  report.rss_end = daemon.ResidentKiB();
  std::this_thread::sleep_for(std::chrono::duration<double>(settle_s));
  report.rss_after = daemon.ResidentKiB();
  report.anon_after = daemon.StatusKiB("RssAnon");
  return report;
}

namespace {
double MiB(int64_t kib) { return kib / 1024.0; }
}  // namespace

void PrintHoarding(const HoardReport& r, int sessions) {
  std::printf("## (h) Hoarding: sessions closed, their segments' descriptors kept\n\n");
  std::printf(
      "One client (this process) opens %d sessions one after another on the daemon's socket, "
      "keeps each segment's descriptor and closes the connection (the session ends); busy or "
      "limit_exceeded answers are waited out and retried. Measured 1 s after the daemon showed "
      "no session: the kept descriptors' files (allocated: st_blocks x 512), the daemon's "
      "VmRSS, the system's Shmem (/proc/meminfo; other processes on the machine move it "
      "too).\n\n",
      sessions);
  if (!r.error.empty()) std::printf("Stopped early: %s\n\n", r.error.c_str());
  std::printf("| what | value |\n| --- | --: |\n");
  std::printf("| sessions opened and closed | %d (%d refusals retried) in %.2f s |\n", r.opened,
              r.refusals, r.seconds);
  std::printf("| sessions open afterwards | %d |\n", r.sessions_open);
  std::printf("| kept descriptors: file size, summed | %.1f MiB |\n", r.kept.size / 1048576.0);
  std::printf("| kept descriptors: memory allocated, summed | **%.1f MiB** |\n",
              r.kept.allocated / 1048576.0);
  std::printf("| daemon VmRSS before / after | %.1f / %.1f MiB |\n", MiB(r.rss_before),
              MiB(r.rss_after));
  std::printf(
      "| system Shmem before / sessions closed / descriptors closed | %.1f / %.1f (%+.1f) "
      "/ %.1f MiB |\n\n",
      MiB(r.shmem_before), MiB(r.shmem_after), MiB(r.shmem_after - r.shmem_before),
      MiB(r.shmem_released));
}

void PrintKilledClient(const KilledClientReport& r, const KilledClientSetup& setup) {
  std::printf("## (i) A client killed while its step runs\n\n");
  if (setup.neighbour_triangles > 0) {
    std::printf(
        "A first client (a child process) uploads ScalingScene of about %lld triangles and "
        "steps it (method %s, resolution %d, contacts): long GL views. ",
        static_cast<long long>(setup.neighbour_triangles), setup.method.c_str(), setup.resolution);
  }
  std::printf(
      "A child process opens a session, uploads ScalingScene of about %lld triangles and "
      "steps it the same way; it is killed with SIGKILL after its step ran %.1f s. The "
      "daemon's mapping of its segment (/proc/<pid>/maps) and the memory the segment's file "
      "holds (/proc/<pid>/map_files, st_blocks x 512) are read every 10 ms.\n\n",
      static_cast<long long>(setup.triangles), r.step_seconds_before_kill);
  if (!r.error.empty()) {
    std::printf("Not measured: %s\n\n", r.error.c_str());
    return;
  }
  std::printf("| what | value |\n| --- | --: |\n");
  std::printf("| segment memory at the kill | %.1f MiB |\n", r.allocated_at_kill / 1048576.0);
  std::printf("| segment memory gone after | **%.2f s** |\n", r.freed_after_s);
  std::printf(
      "| segment unmapped after (its worker ended: its step stopped, its scene freed) | "
      "%.2f s |\n",
      r.unmapped_after_s);
  std::printf("| daemon VmRSS at the kill / as its worker ended | %.1f / %.1f MiB |\n\n",
              MiB(r.rss_at_kill), MiB(r.rss_after));
}

void PrintLargeFlood(const BigFloodReport& r) {
  std::printf("## (j) A flood of large datagrams\n\n");
  std::printf(
      "One thread of this process publishes %lld-byte datagrams of random bytes on the "
      "daemon's session request channels 1-100 (all of them subscribed: each is received, "
      "queued and dropped by the size cap) as fast as it can for %.1f s; then nothing.\n\n",
      static_cast<long long>(r.bytes), r.seconds);
  if (!r.error.empty()) {
    std::printf("Not measured: %s\n\n", r.error.c_str());
    return;
  }
  std::printf("| what | value |\n| --- | --: |\n");
  std::printf("| datagrams sent | %lld (%.0f/s) |\n", static_cast<long long>(r.sent),
              r.sent / std::max(1e-9, r.seconds));
  std::printf("| daemon VmRSS before / at the flood's end / drained | %.1f / %.1f / %.1f MiB |\n",
              MiB(r.rss_before), MiB(r.rss_end), MiB(r.rss_after));
  std::printf("| left in the daemon (VmRSS, RssAnon) | **%+.1f MiB**, %+.1f MiB |\n\n",
              MiB(r.rss_after - r.rss_before), MiB(r.anon_after - r.anon_before));
}

}  // namespace far::study
