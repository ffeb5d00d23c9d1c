#include "socket_server.h"

#include <poll.h>

#include <algorithm>
#include <string>

#include "log_limiter.h"

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/message.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_layout.h"

namespace far::server {
namespace {

namespace wire = far_lcm;

wire::open_session_reply_t OpenReply(int64_t request_id) {
  wire::open_session_reply_t reply{};
  reply.protocol_version = protocol::kProtocolVersion;
  reply.request_id = request_id;
  reply.status_name = "ok";
  return reply;
}

// The open reply of an accepted session: its segment's layout, its channels and its limits.
void SetAccepted(wire::open_session_reply_t& reply, const Session& session,
                 const DaemonConfig& config) {
  const auto& layout = session.segment->layout();
  const protocol::RingLimits limits = RingLimitsOf(config);
  reply.status = protocol::kWireOk;
  reply.session_id = session.id;
  reply.shm_bytes = static_cast<int64_t>(layout.segment_size);
  reply.ring_layout_version = static_cast<int32_t>(protocol::kLayoutVersion);
  reply.update_ring_bytes = static_cast<int64_t>(layout.update_ring_capacity);
  reply.reply_ring_bytes = static_cast<int64_t>(layout.reply_ring_capacity);
  reply.lcm_url = config.lcm_url;
  reply.request_channel = session.request_channel;
  reply.session_reply_channel = session.reply_channel;
  reply.max_objects =
      static_cast<int32_t>(std::min<int64_t>(config.max_objects_per_session, INT32_MAX));
  reply.max_vertices_per_object = static_cast<int32_t>(limits.max_vertices);
  reply.max_triangles_per_object = static_cast<int32_t>(limits.max_triangles);
  reply.max_reply_pairs = config.max_reply_pairs;
  reply.step_deadline_ms = config.step_deadline_ms;
}

void SetRefusal(wire::open_session_reply_t& reply, const Error& error) {
  reply.status = protocol::ToWireStatus(error.code);
  reply.status_name = far::ToString(error.code);
  reply.message = error.message;
}

}  // namespace

int SocketServer::PendingOf(uid_t uid) const {
  return static_cast<int>(std::count_if(pending_.begin(), pending_.end(),
                                        [uid](const Pending& p) { return p.peer.uid == uid; }));
}

int SocketServer::MaxPendingPerUser() const { return std::max(4, config_.max_sessions_per_user); }

void SocketServer::AcceptAll() {
  while (auto connection = listener_->Accept()) {
    const protocol::PeerCredentials peer = connection->peer();
    if (PendingOf(peer.uid) >= MaxPendingPerUser()) {
      stats_.CountRejected("too_many_connections", "user " + std::to_string(peer.uid) + " has " +
                                                       std::to_string(MaxPendingPerUser()) +
                                                       " connections waiting");
      continue;  // closed as it goes out of scope
    }
    pending_.push_back({std::move(*connection), peer, Clock::now() + kHandshakeTimeout});
  }
  // Out of descriptors: the listener closed one waiting connection unanswered, and is left
  // alone for a while, until connections close (it stays readable: polling it would spin).
  if (listener_->out_of_descriptors()) {
    stats_.CountRejected("out_of_descriptors",
                         "far-daemon has no file descriptor left (RLIMIT_NOFILE): a connection "
                         "was closed unanswered");
    listener_paused_until_ = Clock::now() + kOutOfDescriptorsPause;
  }
}

void SocketServer::Handshake(Pending& pending) {
  auto message =
      pending.connection.Receive(protocol::kMaxControlMessageBytes, std::chrono::milliseconds(0));
  if (!message) {
    if (message.error().code != ErrorCode::kUnavailable)
      stats_.CountRejected(far::ToString(message.error().code), message.error().message);
    return;
  }
  auto type = protocol::IdentifyMessage(message->bytes.data(), message->bytes.size());
  if (type && *type == protocol::MessageType::kOpenSession) return Open(pending, message->bytes);
  if (type && *type == protocol::MessageType::kStatusRequest) {
    auto request = protocol::DecodeMessage<wire::status_request_t>(
        message->bytes.data(), message->bytes.size(), protocol::kMaxControlMessageBytes);
    if (!request) return stats_.CountRejected(far::ToString(request.error().code), "status");
    auto reply =
        protocol::EncodeMessage(MakeStatusReply(status_, pending.peer.uid, request->request_id));
    if (reply) (void)pending.connection.Send(*reply);
    return;
  }
  stats_.CountRejected("parse_error", "a local connection that is neither open nor status");
}

void SocketServer::Open(Pending& pending, std::span<const uint8_t> bytes) {
  const uid_t uid = pending.peer.uid;
  auto message = protocol::DecodeMessageAnyVersion<wire::open_session_t>(
      bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
  if (!message) return stats_.CountRejected(far::ToString(message.error().code), "open");
  wire::open_session_reply_t reply = OpenReply(message->request_id);
  auto refuse = [&](const Error& error) {
    SetRefusal(reply, error);
    stats_.CountError(reply.status_name);
    stats_.CountRefusedOpen();
    LogForClient(spdlog::level::warn, uid, "open_refused",
                 "event=open_refused uid={} reason=\"{}\"", uid, ToString(error));
    if (auto out = protocol::EncodeMessage(reply)) (void)pending.connection.Send(*out);
  };
  auto [rate, inserted] =
      open_rate_.try_emplace(uid, config_.max_opens_per_second_per_user,
                             std::max(1.0, config_.max_opens_per_second_per_user));
  if (!rate->second.Allow()) {
    return refuse(MakeError(ErrorCode::kBusy, "max_opens_per_second_per_user: user " +
                                                  std::to_string(uid) +
                                                  " opens sessions faster than " +
                                                  FormatRate(rate->second.rate()) + "/s"));
  }
  if (auto ok = protocol::internal::CheckProtocolVersion(protocol::MessageType::kOpenSession,
                                                         message->protocol_version);
      !ok) {
    return refuse(ok.error());
  }
  auto params = protocol::ValidateOpenSession(*message);
  if (!params) return refuse(params.error());
  auto session = sessions_.Open(*params, pending.peer);
  if (!session) return refuse(session.error());
  SetAccepted(reply, **session, config_);
  auto out = protocol::EncodeMessage(reply);
  // The daemon keeps its own descriptor: it releases the segment's memory when the session
  // ends, whatever the client keeps (ShmSegment::Release).
  Result<void> sent =
      out ? pending.connection.Send(*out, (*session)->segment->fd()) : Result<void>(out.error());
  if (!sent) {
    sessions_.Close((*session)->id);
    (*session)->worker_done = true;  // none will start: reaped (and its budget given back) now
    LogForClient(spdlog::level::warn, uid, "open_failed", "event=open_failed uid={} reason=\"{}\"",
                 uid, sent.error().message);
    return;
  }
  // Said before the worker starts: from then on the segment is the worker's, which frees it as
  // soon as the session closes, and another thread may close it (a shutdown, a faulted ring).
  LogForClient(spdlog::level::info, uid, "session_open",
               "event=session_open session={} uid={} pid={} client=\"{}\" segment={}",
               (*session)->id, uid, pending.peer.pid, (*session)->client_name,
               (*session)->segment->name());
  connections_.emplace((*session)->id, std::move(pending.connection));
  StartSessionWorker(*session, workers_);
}

void SocketServer::DropClosedSessions() {
  for (auto it = connections_.begin(); it != connections_.end();) {
    // Closed by the daemon: closing the connection tells the client at once.
    if (sessions_.Find(it->first) == nullptr) {
      it = connections_.erase(it);
    } else {
      ++it;
    }
  }
}

void SocketServer::Run(const std::atomic<bool>& stop) {
  while (!stop) {
    // (poll ignores a negative descriptor: revents stays 0)
    const bool listening = Clock::now() >= listener_paused_until_;
    std::vector<pollfd> fds = {{listening ? listener_->fd() : -1, POLLIN, 0}};
    for (const Pending& p : pending_) fds.push_back({p.connection.fd(), POLLIN, 0});
    std::vector<int64_t> ids;
    for (const auto& [id, connection] : connections_) {
      fds.push_back({connection.fd(), POLLIN | POLLRDHUP, 0});
      ids.push_back(id);
    }
    poll(fds.data(), fds.size(), 100);
    // fds[1 + i] is pending_[i] only for the connections polled: those accepted now come after
    // them, and wait for their first message until the next turn.
    const size_t polled = pending_.size();
    if (fds[0].revents & POLLIN) AcceptAll();
    // Connections that spoke (or hung up) are done after their handshake; silent ones expire.
    std::vector<Pending> waiting;
    const auto now = Clock::now();
    for (size_t i = 0; i < pending_.size(); ++i) {
      Pending& p = pending_[i];
      if (i < polled && fds[1 + i].revents != 0) {
        Handshake(p);
      } else if (now >= p.deadline) {
        stats_.CountRejected("timeout", "a local connection said nothing");
      } else {
        waiting.push_back(std::move(p));
      }
    }
    pending_ = std::move(waiting);
    const size_t first = fds.size() - ids.size();
    for (size_t k = 0; k < ids.size(); ++k) {
      if (fds[first + k].revents == 0) continue;
      auto it = connections_.find(ids[k]);
      if (it == connections_.end()) continue;
      // A client sends nothing after its open: anything readable is its end of the session.
      (void)it->second.Receive(protocol::kMaxControlMessageBytes, std::chrono::milliseconds(0));
      if (it->second.PeerClosed() || (fds[first + k].revents & (POLLHUP | POLLERR | POLLRDHUP))) {
        if (auto closed = sessions_.Close(ids[k])) {
          LogForClient(spdlog::level::info, closed->uid, "session_close",
                       "event=session_close session={} reason=\"the client closed its connection\"",
                       ids[k]);
        }
        connections_.erase(it);
      }
    }
    DropClosedSessions();
    sessions_.ReapWorkers();
  }
  // The sessions' connections stay open until the server is destroyed: the daemon tells their
  // clients why their sessions end first, and closing a connection would say less, sooner.
  pending_.clear();
}

}  // namespace far::server
