#include "status_reply.h"

#include <unistd.h>

#include <fstream>

#include "far/model/version.h"
#include "far/protocol/channels.h"
#include "far/protocol/version.h"

namespace far::server {
namespace {

// The process' resident memory (/proc/self/statm's second field, in pages); 0 if unreadable.
int64_t ResidentBytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size_pages = 0, resident_pages = 0;
  if (!(statm >> size_pages >> resident_pages)) return 0;
  return resident_pages * sysconf(_SC_PAGESIZE);
}

}  // namespace

far_lcm::status_reply_t MakeStatusReply(const StatusSources& sources, uid_t asker,
                                        int64_t request_id) {
  const DaemonConfig& config = sources.config;
  far_lcm::status_reply_t reply{};
  reply.protocol_version = protocol::kProtocolVersion;
  reply.request_id = request_id;
  reply.daemon_version = kVersion;
  reply.daemon_name = config.name;
  reply.gl_renderer = sources.gl_renderer.empty() ? "none" : sources.gl_renderer;
  reply.gl_device = sources.gl_device.empty() ? "none" : sources.gl_device;
  reply.lcm_url = config.lcm_url;
  reply.channel_prefix = protocol::ChannelPrefix(config.name);
  reply.uptime_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                        std::chrono::steady_clock::now() - sources.started)
                        .count();
  reply.max_sessions = config.max_sessions;
  reply.max_sessions_per_user = config.max_sessions_per_user;
  const DaemonStats::Snapshot stats = sources.stats.Read();
  reply.steps_total = stats.steps_total;
  reply.errors_total = stats.errors_total;
  reply.rejected_messages_total = stats.rejected_total;
  reply.latency_p50_ms = stats.p50_ms;
  reply.latency_p90_ms = stats.p90_ms;
  reply.latency_p99_ms = stats.p99_ms;
  reply.latency_max_ms = stats.max_ms;
  reply.latency_samples = stats.latency_samples;
  const auto sessions = sources.sessions.Sessions();
  reply.sessions_open = static_cast<int32_t>(sessions.size());
  for (const auto& session : sessions) {
    if (asker != 0 && session->uid != asker) continue;
    reply.session_id.push_back(session->id);
    reply.session_uid.push_back(static_cast<int32_t>(session->uid));
    reply.session_pid.push_back(static_cast<int32_t>(session->pid));
    reply.session_client_name.push_back(session->client_name);
    reply.session_steps.push_back(session->steps);
    reply.session_objects.push_back(session->num_objects);
    reply.session_triangles.push_back(session->num_triangles);
    std::lock_guard lock(session->latency_mutex);
    reply.session_latency_p50_ms.push_back(session->latency.Quantile(0.5));
    reply.session_latency_p99_ms.push_back(session->latency.Quantile(0.99));
  }
  reply.num_sessions = static_cast<int32_t>(reply.session_id.size());
  for (const auto& [kind, count] : stats.errors_by_kind) {
    reply.error_kind.push_back(kind);
    reply.error_count.push_back(count);
  }
  reply.num_error_kinds = static_cast<int32_t>(reply.error_kind.size());
  reply.daemon_pid = static_cast<int32_t>(getpid());
  reply.opens_refused_total = stats.opens_refused_total;
  reply.memory_rss_bytes = ResidentBytes();
  reply.segment_bytes = sources.budget.used(BudgetKind::kSegmentBytes);
  reply.gpu_name = sources.gpu_names;
  reply.num_gpu_names = static_cast<int32_t>(reply.gpu_name.size());
  for (const auto& [method, steps] : stats.steps_by_method) {
    reply.method_name.push_back(method);
    reply.method_steps.push_back(steps);
  }
  reply.num_methods = static_cast<int32_t>(reply.method_name.size());
  return reply;
}

}  // namespace far::server
