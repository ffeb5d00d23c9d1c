#pragma once

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "metrics.h"
#include "status_reply.h"

#include "far/base/result.h"

namespace prometheus {
class Exposer;
class Collectable;
}  // namespace prometheus

namespace far::server {

/// The daemon's metrics (MetricFamilies of its status as root sees it, with the latency sum),
/// in Prometheus' text format, version 0.0.4.
std::vector<prometheus::MetricFamily> CollectMetrics(const StatusSources& sources, bool up);

/// Families in Prometheus' text format (prometheus::TextSerializer).
std::string MetricsText(const std::vector<prometheus::MetricFamily>& families);

/// Publishes the metrics the configuration asks for (docs/daemon.md, "Metrics"):
///  - metrics_file: written at Start, every metrics_interval_s on a thread of its own, and a
///    last time at Stop (far_up 0);
///  - metrics_port: /metrics on 127.0.0.1:metrics_port (prometheus::Exposer's own threads),
///    collected at each scrape.
/// `sources` is aliased: it must outlive *this*.
class MetricsExport {
 public:
  /// Starts what `config` asks for (nothing when neither is set). Errors: kIoError (the first
  /// write of metrics_file), kUnavailable (the port cannot be listened on, e.g. taken).
  static Result<std::unique_ptr<MetricsExport>> Start(const DaemonConfig& config,
                                                      const StatusSources& sources);
  /// Stops the writer and the port, and writes the last file (far_up 0). Idempotent; not
  /// thread-safe (the daemon's Run calls it once it has closed every session).
  void Stop();
  ~MetricsExport();

 private:
  MetricsExport(const DaemonConfig& config, const StatusSources& sources);
  void WriteFile(bool up);
  void WriterLoop();

  const DaemonConfig& config_;
  const StatusSources& sources_;
  std::shared_ptr<prometheus::Collectable> collectable_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  std::thread writer_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;          // guarded by mutex_
  bool stopped_ = false;       // Stop ran
  bool last_write_ok_ = true;  // only the writer (then Stop) touches it: log changes only
};

}  // namespace far::server
