#include "session_registry.h"

#include <malloc.h>

#include <algorithm>
#include <string>

#include <spdlog/spdlog.h>

#include "far/protocol/channels.h"
#include "far/protocol/ring_layout.h"

namespace far::server {
namespace {

// The ring sizes of a new session's segment, as its client asked: smaller than the daemon's
// are fine, larger ones are refused.
Result<protocol::SegmentOptions> SegmentOptionsFor(const DaemonConfig& config,
                                                   const protocol::OpenSessionParams& params) {
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
  return options;
}

// A new session's state around its segment: its channels, its rings' ends, its request rate.
std::shared_ptr<Session> NewSession(const DaemonConfig& config, int64_t id,
                                    const protocol::PeerCredentials& peer,
                                    const std::string& client_name,
                                    std::unique_ptr<protocol::ShmSegment> segment) {
  auto session = std::make_shared<Session>();
  session->id = id;
  session->uid = peer.uid;
  session->pid = peer.pid;
  session->segment = std::move(segment);
  session->client_name = client_name;
  session->key = session->segment->session_key();
  const std::string prefix = protocol::ChannelPrefix(config.name);
  session->request_channel = protocol::SessionRequestChannel(prefix, id);
  session->reply_channel = protocol::SessionReplyChannel(prefix, id);
  session->updates = std::make_unique<protocol::UpdateReader>(session->segment->update_ring(),
                                                              RingLimitsOf(config));
  session->replies = std::make_unique<protocol::RingWriter>(session->segment->reply_ring());
  session->request_rate = RateLimiter(config.max_requests_per_second,
                                      std::max(8.0, config.max_requests_per_second / 20));
  session->last_active = Clock::now().time_since_epoch().count();
  return session;
}

}  // namespace

Result<std::shared_ptr<Session>> SessionRegistry::Open(const protocol::OpenSessionParams& params,
                                                       const protocol::PeerCredentials& peer) {
  auto options = SegmentOptionsFor(config_, params);
  if (!options) return options.error();
  int64_t id = 0;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
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
  // The user's share of the sessions and of their segments' bytes, before the segment takes
  // its memory. Not under mutex_: making room closes other sessions, which takes it.
  const uint64_t segment_bytes =
      protocol::MakeSegmentLayout(options->update_ring_bytes, options->reply_ring_bytes)
          .segment_size;
  if (auto admitted =
          budget_.Admit(id, peer.uid, BudgetAmounts::Session(static_cast<int64_t>(segment_bytes)));
      !admitted) {
    return admitted.error();
  }
  auto segment = protocol::ShmSegment::Create(static_cast<uint64_t>(id), *options);
  if (!segment) {
    budget_.Leave(id);
    return segment.error();
  }
  auto session = NewSession(config_, id, peer, params.client_name, std::move(*segment));
  std::lock_guard lock(mutex_);
  if (stopping_) {
    budget_.Leave(id);
    return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
  }
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
    // (its worker left the budget as it ended; one that never started leaves it here)
    budget_.Leave(session->id);
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

std::vector<int64_t> SessionRegistry::IdleSessions(Clock::time_point now,
                                                   Clock::duration timeout) const {
  std::vector<int64_t> idle;
  std::lock_guard lock(mutex_);
  for (const auto& [id, session] : sessions_) {
    const Clock::time_point active{Clock::duration(session->last_active.load())};
    if (!session->stepping && now - active >= timeout) idle.push_back(id);
  }
  return idle;
}

}  // namespace far::server
