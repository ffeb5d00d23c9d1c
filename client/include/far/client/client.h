#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "far/base/result.h"
#include "far/base/stage.h"
#include "far/model/mesh.h"
#include "far/model/scene.h"
#include "far/model/step_request.h"
#include "far/model/step_result.h"

namespace far::client {

namespace internal {
struct ClientAccess;
}  // namespace internal

/// The name of the daemon a client talks to when none is given (far-daemon --name).
inline constexpr std::string_view kDefaultDaemonName = "far";

/// How to reach a daemon and how long to wait for it.
struct ClientOptions {
  /// The daemon's name: its socket is <dir>/<name>.sock, dir as far-daemon chooses it
  /// ($FAR_SOCKET_DIR, else /run/far, else $XDG_RUNTIME_DIR/far, else /tmp/far-<uid> or, when
  /// another user holds that, $HOME/.far/run-<host>; docs/daemon.md, "Where it listens").
  /// "auto": the daemon of the job's GPU on this machine, else the least loaded
  /// (far/client/discovery.h). "" (the default): $FAR_DAEMON when set and no socket_path is
  /// given, so that a scheduler can point every client of a job at a daemon; else "far".
  std::string daemon;
  std::string socket_path;  ///< the daemon's socket, when not the default for `daemon`
  /// The LCM URL of the session's channels; "" = the one the daemon names when it opens the
  /// session (the usual case: clients need no LCM configuration).
  std::string lcm_url;
  std::string client_name = "far-client";  ///< shown in the daemon's status and logs
  /// How long Connect and Status keep trying to reach a daemon that is not there (yet): the
  /// answer "no daemon" comes after this; a daemon started at the same time is found.
  std::chrono::milliseconds connect_timeout{1000};
  /// How long Connect waits for the daemon to answer a probe over LCM, which shows that the
  /// daemon hears this client's steps and the client its replies. A daemon in another network
  /// namespace (or any other reason LCM does not get through) is an error after this, naming
  /// the likely cause, instead of a first step that waits out `timeout`.
  std::chrono::milliseconds hear_timeout{1000};
  /// The longest Step waits for its reply. It waits only while the daemon is alive: a daemon
  /// that stops or restarts ends the wait at once. While it waits, a request the daemon has not
  /// acknowledged is sent again after 200 ms (then 400, 800 ms, and every second), and a step
  /// it acknowledged is asked for again after each second without news: a lost datagram costs
  /// about a second, not this limit (docs/protocol.md, "Lost datagrams").
  std::chrono::milliseconds timeout{60000};
  /// Records the session into a far recording, an LCM log file that `far-client replay` runs
  /// again against any daemon and compares (docs/record-replay.md): every ring record, step
  /// request and step reply; never the session key. nullopt (the default): the environment
  /// variable FAR_RECORD names the file, so that any simulator can be recorded unchanged; ""
  /// records nothing whatever FAR_RECORD says. An existing file is never overwritten: the
  /// session records to "<stem>.2<ext>", "<stem>.3<ext>", ... instead (Client::recording_path).
  std::optional<std::string> record_path;
};

/// Where a step is while its reply has not come: the daemon's step_status_t. The daemon says it
/// once the step is its status_after_ms old (5 ms by default; a quicker step is answered by its
/// reply alone), and "queued" at once when the step waits behind another of the session.
struct StepProgress {
  std::string state;           ///< "queued", "started" or "stage"
  int queue_position = 0;      ///< queued: this session's steps ahead of it
  std::optional<Stage> stage;  ///< state "stage": which one
  double elapsed_ms = 0;       ///< since the daemon received the request
};
using ProgressCallback = std::function<void(const StepProgress&)>;

/// The daemon's status, as far-client status prints it. Sessions are the asking user's own
/// (every session for root).
struct DaemonStatus {
  std::string daemon_version, daemon_name, gl_renderer, gl_device, lcm_url, channel_prefix;
  std::string socket_path;
  int64_t uptime_ms = 0, steps_total = 0, errors_total = 0, rejected_messages_total = 0;
  int max_sessions = 0, max_sessions_per_user = 0, sessions_open = 0;
  double latency_p50_ms = 0, latency_p90_ms = 0, latency_p99_ms = 0, latency_max_ms = 0;
  int64_t latency_samples = 0;
  struct Session {
    int64_t id = 0;
    int uid = 0;
    int pid = 0;  ///< the client's process id (as the daemon sees it: SO_PEERCRED)
    std::string client_name;
    int64_t steps = 0;
    int objects = 0;
    int64_t triangles = 0;
    double latency_p50_ms = 0, latency_p99_ms = 0;
  };
  std::vector<Session> sessions;
  std::vector<std::pair<std::string, int64_t>> errors_by_kind;
  int daemon_pid = 0;
  int64_t opens_refused_total = 0;  ///< session opens refused (limits, rate, bad parameters)
  int64_t memory_rss_bytes = 0;     ///< the daemon's resident memory
  int64_t segment_bytes = 0;        ///< the open sessions' shared-memory segments
  /// What schedulers call the daemon's GPU: its device minor number, UUID and PCI address
  /// when it has one (far::GpuIdentifiers), and far-daemon --serves-gpus (docs/cluster.md).
  std::vector<std::string> gpu_names;
  /// Steps answered by each method that ran ("bvh", "gpu", ...), since the daemon started.
  std::vector<std::pair<std::string, int64_t>> steps_by_method;
};

/// One session with far-daemon: a connection to its local socket (the session lives as long as
/// it does), a shared-memory ring for mesh updates, and LCM for step requests and replies.
/// Updates (AddObject, ...) are written to the ring at once and take effect at the next Step.
///
/// Threads (docs/client.md says why, and how one process steps many sessions):
///  - One Client may be used from several threads at once: every call but the destructor is
///    thread-safe. Updates (AddObject, ..., ApplyFrame) are written to the ring one record at a
///    time, in the order the calls take the client's update lock; a step includes every record
///    written whole before it was sent, and a record written while it is being sent goes with
///    it or with the next step (order steps and updates across threads yourself when it
///    matters: the session has one scene). Concurrent Step and StepAsync calls each get their
///    own step, answered in the order they were sent (one session's steps run one at a time).
///    LoadScene and ApplyFrame are not atomic: another thread's step may see part of them.
///  - Close may be called from any thread while others step: their steps fail at once with
///    kUnavailable ("the session is closed"), and so does every later call. The destructor
///    must not run while another thread is inside a call of the same Client.
///  - on_progress runs on the receiving thread, which the process's Clients on one LCM URL
///    share. It must not block, and must not call Step or Close on any Client (they would wait
///    for that very thread: both return kInvalidArgument instead); StepAsync and the update
///    calls are allowed.
///  - Each Client has its own connection, segment and session, so N threads each stepping their
///    own Client run side by side, in one process or several. The Clients of one process on
///    one LCM URL share one LCM instance and one receiving thread (made with the first, ended
///    with the last; each datagram on the URL is then read once per process, not once per
///    Client). Process-wide state, all initialized thread-safely on first use: libsodium
///    (sodium_init, once), one SIGBUS handler for the shared-memory segments (installed once; a
///    SIGBUS outside a segment goes to the handler that was there before), the shared LCM
///    instances, the loss seam of the tests. Connect reads the
///    environment (FAR_RECORD, FAR_SOCKET_DIR, XDG_RUNTIME_DIR, HOME): do not setenv while
///    another thread connects. The library logs nothing and changes no signal disposition but
///    SIGBUS's (sends use MSG_NOSIGNAL: no SIGPIPE).
///
/// Errors are far::Error: kUnavailable when no daemon runs or it went away, kTimeout when a
/// reply does not come in time, the daemon's own error otherwise.
class Client {
 public:
  /// Opens a session, retrying with backoff for options.connect_timeout while no daemon
  /// answers (one may be starting), then proves with a probe over LCM that the daemon hears
  /// this client. When the daemon at the default socket does not (within hear_timeout), the
  /// sockets of the same name in the other socket directories are tried in order
  /// (protocol::SocketDirectories; not with socket_path or $FAR_SOCKET_DIR). Errors:
  /// kUnavailable ("no far-daemon named ...", "far-daemon 'far' at ... opened this session but
  /// hears none of its steps over LCM (...)" with the likely cause, or the session's LCM URL
  /// is memq://, which no other LCM instance can reach), the
  /// daemon's refusal (kLimitExceeded when it has too many sessions, kBusy when this user opens
  /// too fast), kPermissionDenied when its socket or segment cannot be trusted, kIoError when
  /// the recording (record_path, FAR_RECORD) cannot be created.
  static Result<std::unique_ptr<Client>> Connect(const ClientOptions& options = {});
  /// Closes the session (Close) if still open.
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  /// AddObject and SetPose check X_WO with far::CheckPose (finite; quaternion norm within
  /// kQuaternionTolerance of 1) and send it normalized; a pose beyond the tolerance is
  /// kInvalidArgument at once ("set_pose: object 3: X_WO.rotation_wxyz: not a unit quaternion
  /// (norm 1.7): ...") and nothing is written.
  Result<void> AddObject(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO = {});
  Result<void> RemoveObject(uint32_t id);
  Result<void> SetPose(uint32_t id, const Pose& X_WO);
  Result<void> SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV);
  /// Adds every object of a scene.
  Result<void> LoadScene(const Scene& scene);
  /// Applies one animation frame: removals, additions, poses, vertices.
  Result<void> ApplyFrame(const FrameUpdate& frame);

  /// Runs one step of this session's scene and waits for its reply: up to options.timeout
  /// while the daemon is alive, calling `on_progress` (on the receiving thread) as the daemon
  /// reports the step queued, started and at each stage (StepProgress says when it does). A request
  /// with a distance D and the default output (Output::kContacts) asks for Output::kDistancePairs:
  /// the reply holds every triangle pair closer than D, and the contacts as well (far-client
  /// --distance does the same); every other output is sent as given.
  Result<StepResult> Step(const StepRequest& request, const ProgressCallback& on_progress = {});
  /// Sends a step and returns at once; the future holds the reply or the error. The request
  /// is completed as Step says.
  std::future<Result<StepResult>> StepAsync(const StepRequest& request,
                                            ProgressCallback on_progress = {});

  /// Ends the session; later calls fail with kUnavailable.
  Result<void> Close();

  int64_t session_id() const;
  /// The file this session records to ("" when it does not record).
  std::string recording_path() const;

  /// Asks the daemon for its status (retrying for options.connect_timeout like Connect).
  /// Errors: kUnavailable when no daemon answered.
  static Result<DaemonStatus> Status(const ClientOptions& options = {});

 private:
  struct Impl;
  friend struct internal::ClientAccess;  // replay writes recorded ring records bit for bit
  explicit Client(std::unique_ptr<Impl> impl);
  // Connect for one daemon by name or socket (never "auto").
  static Result<std::unique_ptr<Client>> ConnectTo(const ClientOptions& options);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::client
