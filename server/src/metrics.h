#pragma once

#include <cstdint>
#include <vector>

#include "far_lcm/status_reply_t.hpp"
#include <prometheus/metric_family.h>

namespace far::server {

/// What the metrics need beside the status reply.
struct MetricsExtras {
  /// Steps measured since start and their latencies added, read together (DaemonStats): the
  /// latency summary's _count and _sum. The status carries the count, not the sum.
  int64_t latency_samples = 0;
  double latency_sum_ms = 0;
  /// far_up: 1 while the daemon serves; 0 in the last metrics file, written at a clean stop.
  bool up = true;
  /// The gpu method's steps issued in batches (far::ComputeBatcher) and the batches.
  int64_t gpu_batched_steps = 0;
  int64_t gpu_batches = 0;
};

/// Turns a status into Prometheus metric families (docs/daemon.md, "Metrics", lists them): the
/// values `far-client status` shows, in base units (seconds), each sample labelled with the
/// daemon's name (`daemon`), so that several daemons on one node stay apart. Daemon-wide values
/// only: a user's client names and scene sizes stay theirs, as in the status (the totals of
/// objects and triangles are summed over the sessions listed).
/// @pre `status` was made for root (MakeStatusReply(sources, 0, ...)), which lists every
/// session.
std::vector<prometheus::MetricFamily> MetricFamilies(const far_lcm::status_reply_t& status,
                                                     const MetricsExtras& extras);

}  // namespace far::server
