#include "far/client/client.h"

#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "daemon_connection.h"
#include "session_recorder.h"
#include "shared_receiver.h"

#include "far/client/discovery.h"
#include "far/client/internal/client_access.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"
#include "far/protocol/version.h"

namespace far::client {
namespace {

// The public header cannot include protocol headers (they are not installed): its default
// name must stay the protocol's.
static_assert(kDefaultDaemonName == protocol::kDefaultDaemonName);

using protocol::MessageType;
namespace wire = far_lcm;

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// A full update ring is waited on this long at most: the daemon drains it only at a step, so
// a longer wait would only delay the error.
constexpr std::chrono::seconds kRingWait{5};

// Asking again (docs/protocol.md, "Lost datagrams"). A step the daemon has said nothing of is
// asked for again 200 ms after it was sent, then after 400 ms, 800 ms and every second: on
// loopback the daemon acknowledges ("queued") within a millisecond when it hears. Whenever the
// daemon says something of the step, it is left alone for a quiet second, then asked for again
// the same way: its reply may be lost, and the daemon answers a repeat with the reply it kept,
// or with where the step is. A probe at open is sent every 200 ms until options.hear_timeout.
constexpr milliseconds kFirstRetry{200};
constexpr milliseconds kLongestRetry{1000};
constexpr milliseconds kQuietPoll{1000};
constexpr milliseconds kProbeEvery{200};

// The loss seam (internal::SetDatagramLoss): tests lose messages on purpose.
std::mutex g_loss_mutex;
std::function<bool(const internal::Datagram&)> g_loss;
std::atomic<bool> g_loss_set{false};  // no seam, no cost

bool Lost(const internal::Datagram& datagram) {
  if (!g_loss_set.load(std::memory_order_relaxed)) return false;
  std::function<bool(const internal::Datagram&)> lose;
  {
    std::lock_guard lock(g_loss_mutex);
    if (!g_loss) return false;
    lose = g_loss;
  }
  return lose(datagram);
}

// A distance left at the default output (contacts) asks for distance pairs, as far-client's
// --distance does: otherwise the caller gets an empty list and no error.
StepRequest RequestToSend(StepRequest request) {
  if (request.distance && request.output == Output::kContacts) {
    request.output = Output::kDistancePairs;
  }
  return request;
}

}  // namespace

struct Client::Impl {
  ClientOptions options;
  protocol::LocalConnection connection{-1};  // the session lives as long as this does
  // The process's LCM instance and receiving thread for the session's URL, shared with every
  // Client on it; this session's listener on it (0: not listening).
  std::shared_ptr<internal::SharedReceiver> receiver;
  internal::SharedReceiver::ListenerId listener = 0;
  int64_t session_id = 0;
  std::string request_channel, reply_channel;
  std::unique_ptr<protocol::ShmSegment> segment;
  // The update ring's writer: one record at a time (update_mutex), from any caller's thread.
  // A step reads committed_sequence (under send_mutex) instead of the writer, so that it never
  // waits for a write that waits for room in a full ring, which only a step can make.
  std::mutex update_mutex;
  std::unique_ptr<protocol::UpdateWriter> updates;  // under update_mutex
  std::unique_ptr<protocol::RingReader> replies;    // receiving thread only
  protocol::SessionKey key{};
  int64_t last_sealed_id = 0;  // receiving thread only: the daemon's sequence, strictly growing

  protocol::SkippedReplies skipped;  // receiving thread only: reply records read past
  std::string socket_path;           // where the session was opened
  std::string lcm_url;               // the session's LCM URL: the daemon's unless the caller's
  std::string daemon_lcm_url;        // the one the daemon serves
  bool not_heard = false;            // the daemon answered no probe (Listen)

  // Lock order: update_mutex, then send_mutex, then mutex (none is held while user code runs,
  // but on_progress, which runs on the receive thread with none held).
  std::mutex send_mutex;  // request ids are assigned and published in one order
  int64_t next_request_id = 1;
  int64_t next_step_id = 0;
  uint64_t committed_sequence = 0;  // the last update record written whole (WriteUpdate)

  std::mutex mutex;  // pending steps, the probe and the closed state
  std::condition_variable heard_probe;
  bool probe_answered = false;
  struct Pending {
    far_lcm::step_request_t message;  // the last one sent: its request id, for errors
    std::promise<Result<StepResult>> promise;
    ProgressCallback on_progress;
    Clock::time_point next_try;           // when it is asked for again
    milliseconds wait = 2 * kFirstRetry;  // after that, until the try after it
    bool heard = false;                   // the daemon acknowledged it (a status, a reply)
    int sent = 1;                         // requests sent for it
    std::string progress;  // the last state passed to on_progress (repeats are not passed on)
  };
  std::map<int64_t, Pending> pending;  // by step id
  std::optional<Error> closed;         // set when the session ended

  std::atomic<bool> stopping{false};
  bool connection_ended = false;  // receiving thread only: the daemon's end closed (Tick)
  std::unique_ptr<internal::SessionRecorder> recorder;  // null: not recording

  ~Impl() { StopReceiving(); }

  // Opens a session as `options` say, listens on its reply channel and proves with a probe
  // that the daemon hears this client (else *not_heard). Errors: those of Connect.
  static Result<std::unique_ptr<Impl>> Open(const ClientOptions& options, bool* not_heard);
  // Opens a session on the daemon at options.socket_path (or the default socket for the
  // name): the connection, the open handshake, the segment and its rings; no bus yet.
  static Result<std::unique_ptr<Impl>> OpenOn(const ClientOptions& options);
  // Listens on the reply channel through the process's receiver for the URL, and probes
  // (not_heard when no probe was answered within options.hear_timeout).
  Result<void> Listen();

  // No callback of this session runs once this returns (but the one calling it).
  void StopReceiving() {
    stopping = true;
    if (listener != 0) receiver->Detach(listener);
    listener = 0;
  }

  // Signs and publishes a request, unless the loss seam loses it (call with send_mutex held).
  Result<void> Publish(const far_lcm::step_request_t& message, std::string_view kind) {
    if (Lost({true, session_id, kind, message.step_id, {}})) return {};
    auto bytes = protocol::EncodeSigned(message, key);
    if (!bytes) return bytes.error();
    return receiver->Publish(request_channel, *bytes);
  }

  // The daemon said something of a pending step: it is asked for again only after a quiet
  // second (call with `mutex` held).
  static void Acknowledge(Pending& p) {
    p.heard = true;
    p.next_try = Clock::now() + kQuietPoll;
    p.wait = kFirstRetry;
  }

  // Asks again for every pending step whose time has come (the receiving thread).
  void AskAgain() {
    const auto now = Clock::now();
    std::lock_guard send_lock(send_mutex);
    std::vector<far_lcm::step_request_t> due;
    {
      std::lock_guard lock(mutex);
      for (auto& [step_id, p] : pending) {
        if (now < p.next_try) continue;
        p.message.request_id = next_request_id++;
        ++p.sent;
        p.next_try = now + p.wait;
        p.wait = std::min(2 * p.wait, kLongestRetry);
        due.push_back(p.message);
      }
    }
    // A request that cannot be published now is tried again at its next turn.
    for (const auto& message : due) (void)Publish(message, "request");
  }

  // Sends probes until the daemon answers one or `budget` is spent; the number sent, negative
  // when none was answered. Fails when the session ended meanwhile.
  Result<int> Probe(milliseconds budget) {
    const auto deadline = Clock::now() + budget;
    int probes = 0;
    for (;;) {
      {
        std::lock_guard send_lock(send_mutex);
        if (auto sent = Publish(protocol::MakeProbeRequest(session_id, next_request_id++), "probe");
            !sent) {
          return sent.error();
        }
        ++probes;
      }
      std::unique_lock lock(mutex);
      const auto until = std::min(deadline, Clock::now() + kProbeEvery);
      if (heard_probe.wait_until(lock, until, [&] { return probe_answered || closed; })) {
        if (closed) return *closed;
        return probes;
      }
      if (Clock::now() >= deadline) return -probes;
    }
  }

  // Writes update records with `write` (one thread at a time), then makes them part of the next
  // step: the records' sequence and the step that commits them are read together, under
  // send_mutex, so that a step sent meanwhile by another thread either includes a record or
  // leaves it to the next, and the recording says which. `record(sequence, step_id)` records
  // a record written (in ring order: still under update_mutex).
  template <typename Write, typename Record>
  auto WriteUpdate(Write&& write, Record&& record) {
    std::lock_guard update_lock(update_mutex);
    auto written = write(*updates);
    int64_t step_id = 0;
    {
      std::lock_guard send_lock(send_mutex);
      committed_sequence = updates->last_sequence();
      step_id = next_step_id;
    }
    if (written && recorder) record(written->sequence, step_id);
    return written;
  }

  // Refuses a call that would wait for the receive thread from the receive thread itself (an
  // on_progress callback): it would wait out its timeout.
  Result<void> CheckNotReceiving(const char* what) const {
    if (!receiver || !receiver->OnReceivingThread()) return {};
    return MakeError(ErrorCode::kInvalidArgument,
                     std::string(what) +
                         " called from an on_progress callback: the callback runs on the thread "
                         "that receives the replies of every Client of this process on its LCM "
                         "URL (use StepAsync)");
  }

  // Sends a step (StepAsync); its step id, and the future of its reply.
  std::pair<int64_t, std::future<Result<StepResult>>> Send(const StepRequest& request,
                                                           ProgressCallback on_progress);

  // Records how a pending step ended without a reply of its own (call with `mutex` held).
  void RecordError(int64_t step_id, const Pending& p, const Error& error) {
    if (recorder) recorder->ErrorReply({session_id, p.message.request_id, step_id, 0}, error);
  }

  // Ends a pending step with `error`; false when it was no longer pending (answered).
  bool Fail(int64_t step_id, const Error& error) {
    std::lock_guard lock(mutex);
    auto it = pending.find(step_id);
    if (it == pending.end()) return false;
    RecordError(step_id, it->second, error);
    it->second.promise.set_value(error);
    pending.erase(it);
    return true;
  }

  void FailAll(const Error& error) {
    std::lock_guard lock(mutex);
    for (auto& [id, p] : pending) {
      RecordError(id, p, error);
      p.promise.set_value(error);
    }
    pending.clear();
    if (!closed) closed = error;
  }

  void OnStepReply(std::span<const uint8_t> inner) {
    auto full = protocol::ReceiveStepReply(inner, *replies, &skipped);
    if (!full) return;  // (a stub whose record is gone: the step times out with a clear error)
    if (full->step_id == protocol::kProbeStepId) return ProbeAnswered();  // an older daemon's
    auto result = protocol::ParseStepReply(*full);
    std::lock_guard lock(mutex);
    auto it = pending.find(full->step_id);
    if (it == pending.end()) return;  // a step we gave up on (timeout)
    if (recorder) {
      // A reply that does not parse is recorded as the error the caller got.
      if (result || full->status != protocol::kWireOk) {
        recorder->Reply(*full);
      } else {
        RecordError(full->step_id, it->second, result.error());
      }
    }
    if (result) {
      it->second.promise.set_value(std::move(*result));
    } else {
      it->second.promise.set_value(result.error());
    }
    pending.erase(it);
  }

  void ProbeAnswered() {
    {
      std::lock_guard lock(mutex);
      probe_answered = true;
    }
    heard_probe.notify_all();
  }

  void OnStepStatus(const wire::step_status_t& status) {
    if (status.state == protocol::kHeardState) return ProbeAnswered();
    ProgressCallback callback;
    {
      std::lock_guard lock(mutex);
      auto it = pending.find(status.step_id);
      if (it == pending.end()) return;
      Pending& p = it->second;
      Acknowledge(p);
      // A repeat's answer says again where the step is: passed on only when that changed.
      std::string progress = status.state + "/" + status.stage;
      if (!p.on_progress || progress == p.progress) return;
      p.progress = std::move(progress);
      callback = p.on_progress;
    }
    callback({status.state, status.queue_position, ParseStage(status.stage), status.elapsed_ms});
  }

  void OnError(std::span<const uint8_t> inner) {
    auto error = protocol::DecodeMessage<wire::error_t>(inner.data(), inner.size(),
                                                        protocol::kMaxControlMessageBytes);
    if (!error) return;
    Error e = MakeError(protocol::FromWireStatus(error->status), "far-daemon: " + error->message);
    if (error->session_closed) return FailAll(e);
    std::lock_guard lock(mutex);
    for (auto it = pending.begin(); it != pending.end(); ++it) {
      if (it->second.message.request_id == error->request_id) {
        RecordError(it->first, it->second, e);
        it->second.promise.set_value(e);
        pending.erase(it);
        break;
      }
    }
  }

  // Every message of our reply channel is sealed with our key: anything else (a forgery, a
  // replay, another session's) does not open and is ignored.
  void OnReply(std::span<const uint8_t> bytes) {
    auto opened = protocol::OpenSealed(bytes.data(), bytes.size(), session_id, key,
                                       protocol::kMaxStepReplyBytes);
    if (!opened || opened->request_id <= last_sealed_id) return;
    const std::span<const uint8_t> inner = opened->inner;
    auto type = protocol::IdentifyMessage(inner.data(), inner.size());
    if (!type) return;
    std::optional<wire::step_status_t> status;
    if (*type == MessageType::kStepStatus) {
      auto decoded = protocol::DecodeMessage<wire::step_status_t>(
          inner.data(), inner.size(), protocol::kMaxControlMessageBytes);
      if (!decoded) return;
      status = std::move(*decoded);
    }
    // Lost at the seam: as if it never came, its sequence number unseen.
    if (g_loss_set.load(std::memory_order_relaxed) && Lost(DatagramOf(*type, inner, status)))
      return;
    last_sealed_id = opened->request_id;
    if (*type == MessageType::kStepReply) return OnStepReply(inner);
    if (status) return OnStepStatus(*status);
    if (*type == MessageType::kError) return OnError(inner);
  }

  // A received message as the loss seam sees it.
  internal::Datagram DatagramOf(MessageType type, std::span<const uint8_t> inner,
                                const std::optional<wire::step_status_t>& status) const {
    if (status) return {false, session_id, "status", status->step_id, status->state};
    if (type != MessageType::kStepReply) return {false, session_id, "error", -1, {}};
    auto reply = protocol::DecodeMessage<wire::step_reply_t>(inner.data(), inner.size(),
                                                             protocol::kMaxStepReplyBytes);
    return {false, session_id, "reply", reply ? reply->step_id : -1, {}};
  }

  // The receiving thread's timers (SharedReceiver::kTickEvery): steps to ask for again, and
  // the daemon's end of the connection: when it closes (the daemon stopped, restarted or ended
  // the session) every waiting step fails at once.
  void Tick() {
    if (connection_ended || stopping) return;
    AskAgain();
    if (connection.PeerClosed()) {
      connection_ended = true;
      FailAll(MakeError(ErrorCode::kUnavailable,
                        "far-daemon ended the session (it stopped, restarted or closed it)"));
    }
  }

  // Why step `step_id` is still unanswered at the caller's limit: the daemon working on it,
  // or the daemon never acknowledging any of its requests.
  std::string Unanswered(int64_t step_id) {
    int sent = 0;
    bool heard = true;
    {
      std::lock_guard lock(mutex);
      if (auto it = pending.find(step_id); it != pending.end()) {
        sent = it->second.sent;
        heard = it->second.heard;
      }
    }
    const std::string limit = std::to_string(options.timeout.count()) + " ms";
    const std::string step = "step " + std::to_string(step_id);
    if (heard) {
      return step + " was not answered within " + limit +
             ", the client's limit (the daemon is still running; raise the timeout for bigger "
             "scenes)";
    }
    return step + " was never acknowledged within " + limit +
           ", the client's limit: far-daemon "
           "at " +
           socket_path + " heard none of the " + std::to_string(sent) +
           " requests sent "
           "for it over LCM (" +
           lcm_url +
           "), though it answered this session's probe when it "
           "opened. Its datagrams are being lost (a flood on the LCM URL, a receive buffer too "
           "small: docs/protocol.md), or the daemon's LCM thread is stuck";
  }

  Result<void> CheckOpen() {
    std::lock_guard lock(mutex);
    if (closed) return *closed;
    return {};
  }
};

Client::Client(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Client::~Client() { (void)Close(); }

Result<std::unique_ptr<Client::Impl>> Client::Impl::OpenOn(const ClientOptions& options) {
  auto impl = std::make_unique<Impl>();
  Impl& c = *impl;
  c.options = options;
  c.socket_path = internal::SocketPath(options);
  auto connection = internal::ConnectToDaemon(options);
  if (!connection) return connection.error();
  c.connection = std::move(*connection);
  auto opened = internal::OpenSession(c.connection, options);
  if (!opened) return opened.error();
  const wire::open_session_reply_t& reply = opened->reply;
  c.session_id = reply.session_id;
  c.segment = std::move(opened->segment);
  c.key = c.segment->session_key();
  c.updates = std::make_unique<protocol::UpdateWriter>(c.segment->update_ring());
  c.replies = std::make_unique<protocol::RingReader>(c.segment->reply_ring(),
                                                     c.segment->layout().reply_ring_capacity);
  c.request_channel = reply.request_channel;
  c.reply_channel = reply.session_reply_channel;
  // The session's channels are where the daemon says, unless the caller insists.
  c.lcm_url = options.lcm_url.empty() ? reply.lcm_url : options.lcm_url;
  c.daemon_lcm_url = reply.lcm_url;
  return impl;
}

Result<void> Client::Impl::Listen() {
  if (protocol::IsInProcessUrl(lcm_url)) {
    // Every step would wait out its timeout: no message leaves a memq:// LCM instance.
    return MakeError(ErrorCode::kUnavailable,
                     "the session's LCM URL is " + lcm_url +
                         ", which carries messages only within one LCM instance: no client can "
                         "reach the daemon's channels. Start far-daemon with a udpm:// URL "
                         "(its default) or give the client one with --lcm-url / "
                         "ClientOptions::lcm_url");
  }
  auto shared = internal::SharedReceiver::For(lcm_url);
  if (!shared) return shared.error();
  receiver = std::move(*shared);
  listener = receiver->Attach(
      reply_channel, {[this](std::span<const uint8_t> b) { OnReply(b); }, [this] { Tick(); }});
  // The daemon must hear this client's steps, and the client its replies: a probe proves both
  // before the first step, instead of a first step that waits out its timeout.
  const auto start = Clock::now();
  auto probes = Probe(options.hear_timeout);
  if (!probes) return probes.error();
  if (*probes > 0) return {};
  StopReceiving();
  internal::NotHeard what{
      socket_path, connection.peer().pid,
      lcm_url,     daemon_lcm_url,
      -*probes,    std::chrono::duration_cast<milliseconds>(Clock::now() - start)};
  not_heard = true;
  return MakeError(ErrorCode::kUnavailable, internal::NotHeardMessage(options, what));
}

Result<std::unique_ptr<Client::Impl>> Client::Impl::Open(const ClientOptions& options,
                                                         bool* not_heard) {
  auto impl = OpenOn(options);
  if (!impl) return impl.error();
  if (auto listening = (*impl)->Listen(); !listening) {
    *not_heard = (*impl)->not_heard;
    return listening.error();
  }
  auto recorder = internal::StartRecording(options, (*impl)->session_id);
  if (!recorder) return recorder.error();
  (*impl)->recorder = std::move(*recorder);
  return impl;
}

Result<std::unique_ptr<Client>> Client::Connect(const ClientOptions& given) {
  const ClientOptions options = WithDaemonFromEnvironment(given);
  if (!options.socket_path.empty() || options.daemon != kAutoDaemon) return ConnectTo(options);
  // auto: the daemons this process may use, best first; a full or deaf one passes to the next.
  auto chosen = internal::ChooseDaemons(options);
  if (!chosen) return chosen.error();
  std::string tried;
  for (const ClientOptions& daemon : *chosen) {
    auto client = ConnectTo(daemon);
    if (client) return client;
    tried += "; " + daemon.socket_path + ": " + client.error().message;
  }
  return MakeError(ErrorCode::kUnavailable,
                   "--daemon auto: every daemon it may use refused" + tried);
}

Result<std::unique_ptr<Client>> Client::ConnectTo(const ClientOptions& options) {
  bool not_heard = false;
  auto impl = Impl::Open(options, &not_heard);
  if (impl) return std::unique_ptr<Client>(new Client(std::move(*impl)));
  // The daemon at the first socket cannot hear this client: a daemon of the same name in
  // another socket directory (a user's own, in this network namespace) may be the one meant.
  if (!not_heard) return impl.error();
  std::string tried;
  for (const std::string& path : internal::OtherSocketPaths(options)) {
    ClientOptions other = options;
    other.socket_path = path;
    other.connect_timeout = milliseconds(0);
    auto there = Impl::Open(other, &not_heard);
    if (there) return std::unique_ptr<Client>(new Client(std::move(*there)));
    tried += "; " + path + ": " + there.error().message;
  }
  if (tried.empty()) return impl.error();
  return MakeError(ErrorCode::kUnavailable,
                   impl.error().message + " (other sockets of this name tried" + tried + ")");
}

namespace {
template <typename T>
Result<void> Written(const Result<T>& written, const char* what) {
  if (written) return {};
  Error error = written.error();
  if (error.code == ErrorCode::kTimeout) {
    error.message = std::string(what) + ": the update ring stayed full (" + error.message +
                    "); call Step so the daemon drains it, or open the session with a bigger ring";
  }
  return error;
}

// The pose as it is sent: checked with the model's rule and normalized, so a quaternion written
// with a few decimals is sent as the unit quaternion it stands for, and a bad one is refused
// here, naming the call, instead of failing the next step.
Result<Pose> UnitPose(const Pose& X_WO, const char* what, uint32_t id) {
  Result<Pose> unit = CheckAndNormalizePose(X_WO);
  if (!unit) {
    return MakeError(unit.error().code, std::string(what) + ": object " + std::to_string(id) +
                                            ": X_WO." + unit.error().message);
  }
  return unit;
}
}  // namespace

Result<void> Client::AddObject(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "add_object", id);
  if (!unit) return unit.error();
  auto written = c.WriteUpdate(
      [&](protocol::UpdateWriter& w) { return w.AddObject(id, mesh, motion, *unit, kRingWait); },
      [&](uint64_t sequence, int64_t step_id) {
        c.recorder->AddObject(sequence, step_id, id, mesh, motion, *unit);
      });
  return Written(written, "add_object");
}
Result<void> Client::RemoveObject(uint32_t id) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  auto written = c.WriteUpdate(
      [&](protocol::UpdateWriter& w) { return w.RemoveObject(id, kRingWait); },
      [&](uint64_t sequence, int64_t step_id) { c.recorder->RemoveObject(sequence, step_id, id); });
  return Written(written, "remove_object");
}
Result<void> Client::SetPose(uint32_t id, const Pose& X_WO) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  const Result<Pose> unit = UnitPose(X_WO, "set_pose", id);
  if (!unit) return unit.error();
  auto written =
      c.WriteUpdate([&](protocol::UpdateWriter& w) { return w.SetPose(id, *unit, kRingWait); },
                    [&](uint64_t sequence, int64_t step_id) {
                      c.recorder->SetPose(sequence, step_id, id, *unit);
                    });
  return Written(written, "set_pose");
}
Result<void> Client::SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV) {
  Impl& c = *impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  auto written =
      c.WriteUpdate([&](protocol::UpdateWriter& w) { return w.SetVertices(id, p_MV, kRingWait); },
                    [&](uint64_t sequence, int64_t step_id) {
                      c.recorder->SetVertices(sequence, step_id, id, p_MV);
                    });
  return Written(written, "set_vertices");
}

Result<void> Client::LoadScene(const Scene& scene) {
  for (const SceneObject& object : scene.objects) {
    if (auto ok = AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok) return ok;
  }
  return {};
}

Result<void> Client::ApplyFrame(const FrameUpdate& frame) {
  for (uint32_t id : frame.removals) {
    if (auto ok = RemoveObject(id); !ok) return ok;
  }
  for (const SceneObject& object : frame.additions) {
    if (auto ok = AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok) return ok;
  }
  for (const auto& [id, pose] : frame.poses) {
    if (auto ok = SetPose(id, pose); !ok) return ok;
  }
  for (const auto& [id, mesh] : frame.vertices) {
    if (auto ok = SetVertices(id, mesh.p_MV); !ok) return ok;
  }
  return {};
}

std::pair<int64_t, std::future<Result<StepResult>>> Client::Impl::Send(
    const StepRequest& request, ProgressCallback on_progress) {
  std::promise<Result<StepResult>> promise;
  auto future = promise.get_future();
  std::lock_guard send_lock(send_mutex);
  const int64_t step_id = next_step_id++;
  const auto timeout_ms = static_cast<int32_t>(
      std::min<int64_t>(options.timeout.count(), std::numeric_limits<int32_t>::max()));
  auto message = protocol::MakeStepRequest(session_id, next_request_id++, step_id,
                                           committed_sequence, RequestToSend(request), timeout_ms);
  {
    // Checked where the step becomes pending: a Close on another thread either fails it with
    // the rest (FailAll) or has closed the session already, and the step fails now instead of
    // waiting out its timeout for a reply no thread receives.
    std::lock_guard lock(mutex);
    if (closed) {
      promise.set_value(*closed);
      return {step_id, std::move(future)};
    }
    Pending& p = pending[step_id];
    p.message = message;
    p.promise = std::move(promise);
    p.on_progress = std::move(on_progress);
    p.next_try = Clock::now() + kFirstRetry;
  }
  // Recorded before it is sent, so that the request comes before its reply in the file; a
  // request sent again is the same step, recorded once.
  if (recorder) recorder->Request(message);
  if (auto sent = Publish(message, "request"); !sent) Fail(step_id, sent.error());
  return {step_id, std::move(future)};
}

std::future<Result<StepResult>> Client::StepAsync(const StepRequest& request,
                                                  ProgressCallback on_progress) {
  return impl_->Send(request, std::move(on_progress)).second;
}

Result<StepResult> Client::Step(const StepRequest& request, const ProgressCallback& on_progress) {
  if (auto ok = impl_->CheckNotReceiving("Step"); !ok) return ok.error();
  auto [step_id, future] = impl_->Send(request, on_progress);
  if (future.wait_for(impl_->options.timeout) == std::future_status::ready) return future.get();
  const Error error = MakeError(ErrorCode::kTimeout, impl_->Unanswered(step_id));
  // Answered between the wait and now: the answer stands.
  if (!impl_->Fail(step_id, error)) return future.get();
  return error;
}

Result<void> Client::Close() {
  Impl& c = *impl_;
  if (auto ok = c.CheckNotReceiving("Close"); !ok) return ok;
  if (c.stopping.exchange(true)) return {};
  if (c.listener != 0) c.receiver->Detach(c.listener);
  c.listener = 0;
  // Closing the connection ends the session: the daemon frees it at once.
  c.connection = protocol::LocalConnection(-1);
  c.FailAll(MakeError(ErrorCode::kUnavailable, "the session is closed"));
  return {};
}

int64_t Client::session_id() const { return impl_->session_id; }

std::string Client::recording_path() const {
  return impl_->recorder ? impl_->recorder->path() : std::string();
}

namespace internal {

Result<void> ClientAccess::WriteUpdates(
    Client& client, const std::function<Result<void>(protocol::UpdateWriter&)>& write) {
  Client::Impl& c = *client.impl_;
  if (auto ok = c.CheckOpen(); !ok) return ok;
  std::lock_guard update_lock(c.update_mutex);
  auto written = write(*c.updates);
  std::lock_guard send_lock(c.send_mutex);
  c.committed_sequence = c.updates->last_sequence();
  return written;
}

void SetDatagramLoss(std::function<bool(const Datagram&)> lose) {
  std::lock_guard lock(g_loss_mutex);
  g_loss_set = static_cast<bool>(lose);
  g_loss = std::move(lose);
}

Result<std::unique_ptr<SessionRecorder>> StartRecording(const ClientOptions& options,
                                                        int64_t session_id) {
  std::string path;
  if (options.record_path) {
    path = *options.record_path;
  } else if (const char* env = std::getenv("FAR_RECORD"); env != nullptr) {
    path = env;
  }
  if (path.empty()) return std::unique_ptr<SessionRecorder>();
  SessionRecorder::Info info{options.client_name, "", "", session_id};
  // The daemon's name and renderer tell replay whether GPU answers may differ; a daemon that
  // does not answer leaves them unknown.
  if (auto status = Client::Status(options); status) {
    info.daemon_name = status->daemon_name;
    info.gl_renderer = status->gl_renderer;
  }
  return SessionRecorder::Create(path, info);
}

}  // namespace internal

Result<DaemonStatus> Client::Status(const ClientOptions& given) {
  ClientOptions options = WithDaemonFromEnvironment(given);
  if (options.socket_path.empty() && options.daemon == kAutoDaemon) {
    // The status of the daemon Connect would use first.
    auto chosen = internal::ChooseDaemons(options);
    if (!chosen) return chosen.error();
    options = chosen->front();
  }
  auto connection = internal::ConnectToDaemon(options);
  if (!connection) return connection.error();
  return internal::RequestStatus(*connection, options);
}

}  // namespace far::client
