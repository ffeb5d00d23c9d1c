#include "metrics_export.h"

#include <chrono>
#include <sstream>
#include <stdexcept>

#include "atomic_file.h"
#include <prometheus/collectable.h>
#include <prometheus/exposer.h>
#include <prometheus/text_serializer.h>
#include <spdlog/spdlog.h>

namespace far::server {
namespace {

// Collected at each scrape of the port, on the exposer's threads.
class StatusCollectable : public prometheus::Collectable {
 public:
  explicit StatusCollectable(const StatusSources& sources) : sources_(sources) {}
  std::vector<prometheus::MetricFamily> Collect() const override {
    return CollectMetrics(sources_, /*up=*/true);
  }

 private:
  const StatusSources& sources_;
};

}  // namespace

std::vector<prometheus::MetricFamily> CollectMetrics(const StatusSources& sources, bool up) {
  // The count and the sum from one reading, so that sum/count is a true mean.
  const DaemonStats::Snapshot stats = sources.stats.Read();
  MetricsExtras extras{stats.latency_samples, stats.latency_sum_ms, up};
  if (sources.compute_batcher != nullptr) {
    const ComputeBatcher::Counters batches = sources.compute_batcher->counters();
    extras.gpu_batched_steps = batches.steps;
    extras.gpu_batches = batches.batches;
  }
  return MetricFamilies(MakeStatusReply(sources, /*asker=*/0, /*request_id=*/0), extras);
}

std::string MetricsText(const std::vector<prometheus::MetricFamily>& families) {
  std::ostringstream text;
  prometheus::TextSerializer().Serialize(text, families);
  return text.str();
}

MetricsExport::MetricsExport(const DaemonConfig& config, const StatusSources& sources)
    : config_(config), sources_(sources) {}

Result<std::unique_ptr<MetricsExport>> MetricsExport::Start(const DaemonConfig& config,
                                                            const StatusSources& sources) {
  std::unique_ptr<MetricsExport> metrics(new MetricsExport(config, sources));
  if (!config.metrics_file.empty()) {
    // The first write at once: a file that cannot be written is a start-up error.
    if (auto written =
            WriteFileAtomically(config.metrics_file, MetricsText(CollectMetrics(sources, true)));
        !written) {
      return MakeError(written.error().code, "metrics_file " + written.error().message);
    }
    metrics->writer_ = std::thread([raw = metrics.get()] { raw->WriterLoop(); });
  }
  if (config.metrics_port != 0) {
    // Loopback only: a node-local agent scrapes it; nothing off the host may.
    const std::string address = "127.0.0.1:" + std::to_string(config.metrics_port);
    try {
      metrics->exposer_ = std::make_unique<prometheus::Exposer>(address, /*num_threads=*/2);
    } catch (const std::exception& e) {
      metrics->Stop();
      return MakeError(ErrorCode::kUnavailable, "metrics_port " +
                                                    std::to_string(config.metrics_port) +
                                                    ": cannot listen on " + address + " (" +
                                                    e.what() + "; is the port taken?)");
    }
    metrics->collectable_ = std::make_shared<StatusCollectable>(sources);
    metrics->exposer_->RegisterCollectable(metrics->collectable_);
  }
  if (!config.metrics_file.empty() || config.metrics_port != 0) {
    spdlog::info("event=metrics_export file=\"{}\" interval_s={} port={}", config.metrics_file,
                 config.metrics_interval_s, config.metrics_port);
  }
  return metrics;
}

void MetricsExport::WriteFile(bool up) {
  auto written =
      WriteFileAtomically(config_.metrics_file, MetricsText(CollectMetrics(sources_, up)));
  // One line when writing starts failing and one when it works again, not one per interval.
  if (!written && last_write_ok_) {
    spdlog::warn("event=metrics_file_error message=\"metrics_file {}\"", written.error().message);
  } else if (written && !last_write_ok_) {
    spdlog::info("event=metrics_file_written file=\"{}\"", config_.metrics_file);
  }
  last_write_ok_ = written.ok();
}

void MetricsExport::WriterLoop() {
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(config_.metrics_interval_s));
  auto next = std::chrono::steady_clock::now() + interval;
  std::unique_lock lock(mutex_);
  while (!wake_.wait_until(lock, next, [this] { return stop_; })) {
    lock.unlock();
    WriteFile(/*up=*/true);
    lock.lock();
    // Every interval from the start, not from the end of each write; after a stall (a write
    // that took longer), from now, rather than a burst of writes to catch up.
    next += interval;
    if (const auto now = std::chrono::steady_clock::now(); next < now) next = now + interval;
  }
}

void MetricsExport::Stop() {
  if (stopped_) return;
  stopped_ = true;
  // No scrape runs past here (the exposer's threads end with it).
  exposer_.reset();
  if (writer_.joinable()) {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    writer_.join();
    // The last file: what a cleanly stopped daemon leaves (far_up 0, its final counters).
    WriteFile(/*up=*/false);
  }
}

MetricsExport::~MetricsExport() { Stop(); }

}  // namespace far::server
