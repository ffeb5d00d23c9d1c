#include "daemon_connection.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <thread>

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/version.h"

namespace far::client::internal {
namespace {

using Clock = std::chrono::steady_clock;
namespace wire = far_lcm;

// How long a daemon that accepted the connection may take to answer: it answers once its GL
// context is made, which takes seconds on some drivers.
constexpr std::chrono::seconds kAnswerTimeout{15};

int64_t RandomId() {
  int64_t id = 0;
  protocol::RandomBytes(reinterpret_cast<uint8_t*>(&id), sizeof(id));
  return id & 0x3fffffffffffffff;
}

// The reply to one message on the connection (the daemon answers each with exactly one).
Result<protocol::LocalMessage> Ask(protocol::LocalConnection& connection,
                                   std::span<const uint8_t> request, size_t max_reply,
                                   bool accept_fd) {
  if (auto sent = connection.Send(request); !sent) return sent.error();
  auto reply = connection.Receive(max_reply, kAnswerTimeout, accept_fd);
  if (!reply && reply.error().code == ErrorCode::kUnavailable) {
    return MakeError(ErrorCode::kUnavailable,
                     "far-daemon closed the connection without an answer: it is stopping, or this "
                     "user has more connections waiting than it may hold sessions (far-client "
                     "status counts them under errors, too_many_connections)");
  }
  return reply;
}

// The network namespace of process `pid` ("net:[4026531840]"), "" when it cannot be read (a
// process of another user, or gone).
std::string NetworkNamespaceOf(const std::string& pid) {
  char target[PATH_MAX] = {};
  const std::string link = "/proc/" + pid + "/ns/net";
  const ssize_t n = readlink(link.c_str(), target, sizeof(target) - 1);
  return n > 0 ? std::string(target, static_cast<size_t>(n)) : std::string();
}

// Why the daemon hears nothing, as far as this process can tell.
std::string LikelyCause(const NotHeard& what) {
  const std::string mine = NetworkNamespaceOf("self");
  const std::string theirs =
      what.daemon_pid > 0 ? NetworkNamespaceOf(std::to_string(what.daemon_pid)) : "";
  const std::string pid = std::to_string(what.daemon_pid);
  if (!mine.empty() && !theirs.empty() && mine != theirs) {
    return "It runs in another network namespace (" + theirs + "; this client: " + mine +
           "), and LCM multicast does not cross namespaces. Run the client in the daemon's "
           "(nsenter --net=/proc/" +
           pid +
           "/ns/net ...), or start a daemon in this one and name "
           "its socket (--socket, FAR_SOCKET_DIR)";
  }
  if (what.lcm_url != what.daemon_lcm_url) {
    return "This client sends on " + what.lcm_url +
           " (--lcm-url / ClientOptions::lcm_url) but "
           "the daemon serves " +
           what.daemon_lcm_url + "; leave the client's URL empty";
  }
  if (!mine.empty() && mine == theirs) {
    return "Both run in this network namespace (" + mine +
           "), so multicast is blocked here: "
           "loopback needs multicast (ip link set lo multicast on; ip route add 224.0.0.0/4 dev "
           "lo), and no firewall rule may drop it";
  }
  return "Is it in another network namespace than this client (then run the client in the "
         "daemon's, or name the socket of a daemon in this one: --socket, FAR_SOCKET_DIR), or is "
         "another daemon serving this name?";
}

}  // namespace

std::vector<std::string> OtherSocketPaths(const ClientOptions& options) {
  std::vector<std::string> paths;
  if (!options.socket_path.empty()) return paths;
  const std::vector<std::string> dirs = protocol::SocketDirectories();
  for (size_t i = 1; i < dirs.size(); ++i) {
    const std::string path = dirs[i] + "/" + options.daemon + ".sock";
    struct stat info {};
    if (lstat(path.c_str(), &info) == 0 && S_ISSOCK(info.st_mode)) paths.push_back(path);
  }
  return paths;
}

std::string NotHeardMessage(const ClientOptions& options, const NotHeard& what) {
  const std::string daemon =
      options.socket_path.empty() ? "far-daemon '" + options.daemon + "'" : "far-daemon";
  return daemon + " at " + what.socket_path + " (pid " + std::to_string(what.daemon_pid) +
         ") opened this session but hears none of its steps over LCM (" + what.lcm_url +
         "): it answered none of " + std::to_string(what.probes) + " probes in " +
         std::to_string(what.waited.count()) + " ms. " + LikelyCause(what);
}

std::string SocketPath(const ClientOptions& options) {
  return options.socket_path.empty() ? protocol::DefaultSocketPath(options.daemon)
                                     : options.socket_path;
}

Result<protocol::LocalConnection> ConnectToDaemon(const ClientOptions& options) {
  const std::string path = SocketPath(options);
  if (options.socket_path.empty() && !protocol::IsValidDaemonName(options.daemon)) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        "daemon name '" + options.daemon + "' is not 1..16 of [a-z0-9-] starting with a letter");
  }
  const auto start = Clock::now();
  auto pause = std::chrono::milliseconds(10);
  for (;;) {
    auto connection = protocol::LocalConnection::Connect(path);
    if (connection) return connection;
    const ErrorCode code = connection.error().code;
    // Not there yet (or a dead daemon's socket): a daemon may be starting; anything else is final.
    if (code != ErrorCode::kNotFound && code != ErrorCode::kUnavailable) return connection.error();
    const auto waited = Clock::now() - start;
    if (waited + pause > options.connect_timeout) {
      return MakeError(
          ErrorCode::kUnavailable,
          "no far-daemon named '" + options.daemon + "' is running (" + connection.error().message +
              "; tried for " +
              std::to_string(
                  std::chrono::duration_cast<std::chrono::milliseconds>(waited).count()) +
              " ms). Start one with far-daemon, or name another with --daemon / --socket");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::milliseconds(200));
  }
}

Result<OpenedSession> OpenSession(protocol::LocalConnection& connection,
                                  const ClientOptions& options) {
  wire::open_session_t open{};
  open.protocol_version = protocol::kProtocolVersion;
  open.request_id = RandomId();
  open.client_name = options.client_name;
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes) return bytes.error();
  auto answer = Ask(connection, *bytes, protocol::kMaxControlMessageBytes, /*accept_fd=*/true);
  if (!answer) return answer.error();
  const int fd = answer->fd;
  auto reply = protocol::DecodeMessage<wire::open_session_reply_t>(
      answer->bytes.data(), answer->bytes.size(), protocol::kMaxControlMessageBytes);
  if (!reply || reply->request_id != open.request_id || reply->status != protocol::kWireOk) {
    if (fd >= 0) close(fd);
    if (!reply) return reply.error();
    if (reply->request_id != open.request_id)
      return MakeError(ErrorCode::kParseError, "open_session_reply_t: another request's answer");
    return MakeError(protocol::FromWireStatus(reply->status),
                     "far-daemon refused the session: " + reply->message);
  }
  if (fd < 0) {
    return MakeError(ErrorCode::kParseError,
                     "open_session_reply_t: accepted, but no segment came with it");
  }
  // Map the session's segment (checks seals, size and header) and take its key.
  auto segment = protocol::ShmSegment::Open(fd, static_cast<uint64_t>(reply->session_id));
  if (!segment) return segment.error();
  return OpenedSession{std::move(*reply), std::move(*segment)};
}

Result<DaemonStatus> RequestStatus(protocol::LocalConnection& connection,
                                   const ClientOptions& options) {
  wire::status_request_t request{};
  request.protocol_version = protocol::kProtocolVersion;
  request.request_id = RandomId();
  auto bytes = protocol::EncodeMessage(request);
  if (!bytes) return bytes.error();
  auto answer = Ask(connection, *bytes, protocol::kMaxStatusReplyBytes, /*accept_fd=*/false);
  if (!answer) return answer.error();
  auto reply = protocol::DecodeMessage<wire::status_reply_t>(
      answer->bytes.data(), answer->bytes.size(), protocol::kMaxStatusReplyBytes);
  if (!reply) return reply.error();
  DaemonStatus status;
  status.daemon_version = reply->daemon_version;
  status.daemon_name = reply->daemon_name;
  status.gl_renderer = reply->gl_renderer;
  status.gl_device = reply->gl_device;
  status.lcm_url = reply->lcm_url;
  status.channel_prefix = reply->channel_prefix;
  status.socket_path = SocketPath(options);
  status.uptime_ms = reply->uptime_ms;
  status.max_sessions = reply->max_sessions;
  status.max_sessions_per_user = reply->max_sessions_per_user;
  status.sessions_open = reply->sessions_open;
  status.steps_total = reply->steps_total;
  status.errors_total = reply->errors_total;
  status.rejected_messages_total = reply->rejected_messages_total;
  status.latency_p50_ms = reply->latency_p50_ms;
  status.latency_p90_ms = reply->latency_p90_ms;
  status.latency_p99_ms = reply->latency_p99_ms;
  status.latency_max_ms = reply->latency_max_ms;
  status.latency_samples = reply->latency_samples;
  for (int i = 0; i < reply->num_sessions; ++i) {
    status.sessions.push_back({reply->session_id[i], reply->session_uid[i], reply->session_pid[i],
                               reply->session_client_name[i], reply->session_steps[i],
                               reply->session_objects[i], reply->session_triangles[i],
                               reply->session_latency_p50_ms[i], reply->session_latency_p99_ms[i]});
  }
  for (int i = 0; i < reply->num_error_kinds; ++i) {
    status.errors_by_kind.emplace_back(reply->error_kind[i], reply->error_count[i]);
  }
  status.daemon_pid = reply->daemon_pid;
  status.opens_refused_total = reply->opens_refused_total;
  status.memory_rss_bytes = reply->memory_rss_bytes;
  status.segment_bytes = reply->segment_bytes;
  status.gpu_names = reply->gpu_name;
  for (int i = 0; i < reply->num_methods; ++i)
    status.steps_by_method.emplace_back(reply->method_name[i], reply->method_steps[i]);
  return status;
}

}  // namespace far::client::internal
