#include "session_registry.h"

#include <algorithm>
#include <string>

namespace far::server {
namespace {

SchedulerLimits LimitsOf(const DaemonConfig& config) {
  return SchedulerLimits{static_cast<size_t>(config.max_queued_per_session),
                         static_cast<size_t>(config.max_queued_total),
                         config.max_requests_per_second,
                         std::max(8.0, config.max_requests_per_second / 20)};
}

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

SessionRegistry::SessionRegistry(const DaemonConfig& config)
    : config_(config), scheduler_(LimitsOf(config)) {}

Result<std::shared_ptr<Session>> SessionRegistry::Open(const protocol::OpenSessionParams& params) {
  int64_t id = 0;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
    if (static_cast<int>(sessions_.size()) >= config_.max_sessions) {
      return MakeError(
          ErrorCode::kLimitExceeded,
          "max_sessions: " + std::to_string(config_.max_sessions) + " sessions are open");
    }
    id = next_session_id_++;
  }
  auto segment = MakeSegment(config_, params, id);
  if (!segment) return segment.error();
  auto session = std::make_shared<Session>();
  session->id = id;
  session->segment = std::move(*segment);
  session->client_name = params.client_name;
  session->key = session->segment->session_key();
  session->request_channel = protocol::SessionRequestChannel(id);
  session->reply_channel = protocol::SessionReplyChannel(id);
  session->updates = std::make_unique<protocol::UpdateReader>(session->segment->update_ring(),
                                                              RingLimitsOf(config_));
  session->replies = std::make_unique<protocol::RingWriter>(session->segment->reply_ring());
  session->last_heard_ms = NowMs();
  std::lock_guard lock(mutex_);
  sessions_[id] = session;
  return session;
}

std::shared_ptr<Session> SessionRegistry::Find(int64_t id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second;
}

std::optional<SessionRegistry::Closed> SessionRegistry::Close(int64_t id) {
  Closed closed;
  {
    std::lock_guard lock(mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return std::nullopt;
    closed.session = it->second;
    sessions_.erase(it);
    closed.pending = scheduler_.RemoveSession(id);
    to_free_.push_back(closed.session);
  }
  work_.notify_one();
  return closed;
}

Result<void> SessionRegistry::Queue(StepJob job) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return MakeError(ErrorCode::kUnavailable, "the daemon is shutting down");
    const int64_t id = job.session->id;
    if (auto ok = scheduler_.Push(id, std::move(job)); !ok) return ok;
  }
  work_.notify_one();
  return {};
}

SessionRegistry::Work SessionRegistry::WaitForWork(std::chrono::milliseconds timeout) {
  Work work;
  std::unique_lock lock(mutex_);
  work_.wait_for(lock, timeout,
                 [&] { return stopping_ || scheduler_.size() > 0 || !to_free_.empty(); });
  work.freed.swap(to_free_);
  if (auto next = scheduler_.Pop()) work.job = std::move(next->second);
  work.done = stopping_ && !work.job && work.freed.empty();
  return work;
}

std::vector<std::shared_ptr<Session>> SessionRegistry::Sessions() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Session>> open;
  for (const auto& [id, session] : sessions_) open.push_back(session);
  return open;
}

std::vector<int64_t> SessionRegistry::Silent(int64_t now_ms, int64_t timeout_ms) const {
  std::lock_guard lock(mutex_);
  std::vector<int64_t> silent;
  for (const auto& [id, session] : sessions_) {
    if (now_ms - session->last_heard_ms > timeout_ms) silent.push_back(id);
  }
  return silent;
}

std::vector<std::shared_ptr<Session>> SessionRegistry::TakeAll() {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Session>> all;
  for (auto& [id, session] : sessions_) all.push_back(std::move(session));
  sessions_.clear();
  return all;
}

void SessionRegistry::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_.notify_all();
}

size_t SessionRegistry::queued() const {
  std::lock_guard lock(mutex_);
  return scheduler_.size();
}

}  // namespace far::server
