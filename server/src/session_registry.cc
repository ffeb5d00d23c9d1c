#include "session_registry.h"

#include <malloc.h>

#include <algorithm>
#include <string>

#include <spdlog/spdlog.h>

#include "far/protocol/channels.h"

namespace far::server {
namespace {

// The segment of a new session, with the ring sizes its client asked for: smaller than the
// daemon's are fine, larger ones are refused.
Result<std::unique_ptr<protocol::ShmSegment>> MakeSegment(const DaemonConfig& config,
                                                          const protocol::OpenSessionParams& params,
                                                          int64_t session_id) {
  protocol::SegmentOptions options;
  options.update_ring_bytes =
      params.update_ring_bytes ? params.update_ring_bytes : config.ring_bytes;
  options.reply_ring_bytes = params.reply_ring_bytes ? params.reply_ring_bytes : config.reply_bytes;
  if (options.update_ring_bytes > config.ring_bytes ||
      options.reply_ring_bytes > config.reply_bytes) {
    return MakeError(ErrorCode::kLimitExceeded,
                     "update_ring_bytes/reply_ring_bytes: this daemon allows at most " +
                         std::to_string(config.ring_bytes) + "/" +
                         std::to_string(config.reply_bytes) + " bytes");
  }
  return protocol::ShmSegment::Create(static_cast<uint64_t>(session_id), options);
}

}  // namespace

Result<std::shared_ptr<Session>> SessionRegistry::Open(const protocol::OpenSessionParams& params,
                                                       const protocol::PeerCredentials& peer) {
  int64_t id = 0;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
    if (static_cast<int>(sessions_.size()) >= config_.max_sessions) {
      return MakeError(
          ErrorCode::kLimitExceeded,
          "max_sessions: " + std::to_string(config_.max_sessions) + " sessions are open");
    }
    const auto mine = std::count_if(sessions_.begin(), sessions_.end(), [&](const auto& entry) {
      return entry.second->uid == peer.uid;
    });
    if (mine >= config_.max_sessions_per_user) {
      return MakeError(ErrorCode::kLimitExceeded, "max_sessions_per_user: user " +
                                                      std::to_string(peer.uid) + " has " +
                                                      std::to_string(mine) + " sessions open");
    }
    id = next_session_id_++;
  }
  auto segment = MakeSegment(config_, params, id);
  if (!segment) return segment.error();
  auto session = std::make_shared<Session>();
  session->id = id;
  session->uid = peer.uid;
  session->pid = peer.pid;
  session->segment = std::move(*segment);
  session->client_name = params.client_name;
  session->key = session->segment->session_key();
  const std::string prefix = protocol::ChannelPrefix(config_.name);
  session->request_channel = protocol::SessionRequestChannel(prefix, id);
  session->reply_channel = protocol::SessionReplyChannel(prefix, id);
  session->updates = std::make_unique<protocol::UpdateReader>(session->segment->update_ring(),
                                                              RingLimitsOf(config_));
  session->replies = std::make_unique<protocol::RingWriter>(session->segment->reply_ring());
  session->request_rate = RateLimiter(config_.max_requests_per_second,
                                      std::max(8.0, config_.max_requests_per_second / 20));
  std::lock_guard lock(mutex_);
  if (stopping_) return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
  sessions_[id] = session;
  return session;
}

std::shared_ptr<Session> SessionRegistry::Find(int64_t id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Session>> SessionRegistry::Sessions() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Session>> open;
  for (const auto& [id, session] : sessions_) open.push_back(session);
  return open;
}

size_t SessionRegistry::size() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

namespace {
// Tells a session's worker to end: the running step stops, the queue is dropped. The segment's
// memory goes now, not when the worker ends (which may first finish a GL view, or wait for
// another session's): a client that kept the segment's descriptor holds an empty file, and a
// killed client's segment is freed at once. The worker still owns the segment object and frees
// it as it ends; it cannot have ended yet, since it ends only once `closing` is set below.
void EndSession(Session& session) {
  if (session.segment != nullptr) {
    if (auto released = session.segment->Release(); !released)
      spdlog::warn("event=segment_not_released session={} reason=\"{}\"", session.id,
                   released.error().message);
  }
  session.cancel = true;
  {
    std::lock_guard lock(session.mutex);
    session.closing = true;
    session.queue.clear();
  }
  session.wake.notify_all();
}
}  // namespace

std::shared_ptr<Session> SessionRegistry::Close(int64_t id) {
  std::shared_ptr<Session> session;
  {
    std::lock_guard lock(mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return nullptr;
    session = it->second;
    sessions_.erase(it);
    closed_.push_back(session);
  }
  EndSession(*session);
  return session;
}

std::vector<std::shared_ptr<Session>> SessionRegistry::CloseAll() {
  std::vector<std::shared_ptr<Session>> all;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (auto& [id, session] : sessions_) all.push_back(session);
    sessions_.clear();
    closed_.insert(closed_.end(), all.begin(), all.end());
  }
  for (auto& session : all) EndSession(*session);
  return all;
}

int SessionRegistry::ReapWorkers(bool wait) {
  std::vector<std::shared_ptr<Session>> ended;
  {
    std::lock_guard lock(mutex_);
    auto keep = std::partition(closed_.begin(), closed_.end(), [&](const auto& session) {
      return !wait && !session->worker_done.load();
    });
    ended.assign(keep, closed_.end());
    closed_.erase(keep, closed_.end());
  }
  for (auto& session : ended) {
    if (session->worker.joinable()) session->worker.join();
  }
  const int joined = static_cast<int>(ended.size());
  if (joined > 0) {
    ended.clear();  // the last references: segments and pipelines are gone now
    // Give the freed memory back to the system (glibc keeps it in its arenas otherwise), so
    // that the daemon's RSS returns to its baseline once sessions close.
    malloc_trim(0);
  }
  return joined;
}

}  // namespace far::server
