#include "metrics.h"

#include <optional>
#include <string>
#include <utility>

#include "far/model/step_request.h"

namespace far::server {
namespace {

using prometheus::ClientMetric;
using prometheus::MetricFamily;
using prometheus::MetricType;

// Builds the families, each sample labelled with the daemon's name.
class Families {
 public:
  explicit Families(std::string daemon) : daemon_(std::move(daemon)) {}

  void Gauge(const std::string& name, const std::string& help, double value,
             std::vector<ClientMetric::Label> labels = {}) {
    ClientMetric& metric = Sample(name, help, MetricType::Gauge, std::move(labels));
    metric.gauge.value = value;
  }
  void Counter(const std::string& name, const std::string& help, double value,
               std::vector<ClientMetric::Label> labels = {}) {
    ClientMetric& metric = Sample(name, help, MetricType::Counter, std::move(labels));
    metric.counter.value = value;
  }
  // A family with no sample yet (a counter by kind before the first of any kind): its HELP and
  // TYPE still say it exists.
  void Declare(const std::string& name, const std::string& help, MetricType type) {
    Family(name, help, type);
  }
  ClientMetric& Sample(const std::string& name, const std::string& help, MetricType type,
                       std::vector<ClientMetric::Label> labels) {
    MetricFamily& family = Family(name, help, type);
    ClientMetric& metric = family.metric.emplace_back();
    metric.label.push_back({"daemon", daemon_});
    for (auto& label : labels) metric.label.push_back(std::move(label));
    return metric;
  }
  std::vector<MetricFamily> Take() { return std::move(families_); }

 private:
  MetricFamily& Family(const std::string& name, const std::string& help, MetricType type) {
    if (families_.empty() || families_.back().name != name) {
      families_.push_back(MetricFamily{name, help, type, {}});
    }
    return families_.back();
  }
  std::string daemon_;
  std::vector<MetricFamily> families_;
};

double Seconds(double ms) { return ms / 1000.0; }

// Where a method's steps run: "gpu" for those that need a GL context (the raster methods and
// the compute-shader one), "cpu" for the rest.
std::string DeviceOf(const std::string& method) {
  const std::optional<Method> parsed = ParseMethod(method);
  if (!parsed) return "unknown";
  return NeedsGl(*parsed) ? "gpu" : "cpu";
}

// Steps: counted, by method, batched on the GPU, and their latency.
void AddStepFamilies(const far_lcm::status_reply_t& status, const MetricsExtras& extras,
                     Families& out) {
  out.Counter("far_steps_total", "steps answered since the daemon started, all users",
              static_cast<double>(status.steps_total));
  const std::string by_method_help =
      "steps answered since start by the method that ran (auto's choice), on the GPU or the CPU";
  out.Declare("far_steps_by_method_total", by_method_help, MetricType::Counter);
  for (int i = 0; i < status.num_methods; ++i) {
    out.Counter("far_steps_by_method_total", by_method_help,
                static_cast<double>(status.method_steps[i]),
                {{"method", status.method_name[i]}, {"device", DeviceOf(status.method_name[i])}});
  }
  out.Counter("far_gpu_batched_steps_total",
              "gpu method steps whose GPU work went in a batch with the steps waiting beside it "
              "(--gpu-batch)",
              static_cast<double>(extras.gpu_batched_steps));
  out.Counter("far_gpu_batches_total",
              "batches of gpu method steps issued together; steps over batches is the mean "
              "batch",
              static_cast<double>(extras.gpu_batches));
  ClientMetric& latency = out.Sample(
      "far_step_latency_seconds",
      "step latency, request received to reply ready; quantiles over the last 8192 steps, "
      "count and sum since start",
      MetricType::Summary, {});
  latency.summary.sample_count = static_cast<uint64_t>(extras.latency_samples);
  latency.summary.sample_sum = Seconds(extras.latency_sum_ms);
  latency.summary.quantile = {{0.5, Seconds(status.latency_p50_ms)},
                              {0.9, Seconds(status.latency_p90_ms)},
                              {0.99, Seconds(status.latency_p99_ms)},
                              {1.0, Seconds(status.latency_max_ms)}};
}

}  // namespace

std::vector<MetricFamily> MetricFamilies(const far_lcm::status_reply_t& status,
                                         const MetricsExtras& extras) {
  Families out(status.daemon_name);
  // What the daemon is.
  out.Gauge("far_up", "1 while the daemon serves; 0 in the last file it writes at a clean stop",
            extras.up ? 1 : 0);
  out.Gauge("far_info", "the daemon's version, process id and GL device (value 1)", 1,
            {{"version", status.daemon_version},
             {"gl_renderer", status.gl_renderer},
             {"gl_device", status.gl_device},
             {"pid", std::to_string(status.daemon_pid)}});
  out.Gauge("far_uptime_seconds", "seconds since the daemon started", Seconds(status.uptime_ms));
  // One sample per name a scheduler gives the daemon's GPU: a join with the GPU's own metrics
  // (DCGM's UUID, a Slurm index).
  const std::string gpu_help = "a name schedulers give the daemon's GPU (value 1)";
  out.Declare("far_gpu_info", gpu_help, MetricType::Gauge);
  for (const std::string& name : status.gpu_name)
    out.Gauge("far_gpu_info", gpu_help, 1, {{"gpu", name}});
  out.Gauge("far_memory_rss_bytes", "the daemon's resident memory",
            static_cast<double>(status.memory_rss_bytes));
  out.Gauge("far_segment_bytes", "the open sessions' shared-memory segments together",
            static_cast<double>(status.segment_bytes));
  // Sessions and what they hold.
  out.Gauge("far_sessions_open", "sessions open now, all users", status.sessions_open);
  out.Counter("far_opens_refused_total",
              "session opens refused since start (limits, rate, bad parameters); also counted in "
              "far_errors_total",
              static_cast<double>(status.opens_refused_total));
  out.Gauge("far_sessions_max", "the daemon's session limit, all users (max_sessions)",
            status.max_sessions);
  out.Gauge("far_sessions_max_per_user", "the session limit of one user (max_sessions_per_user)",
            status.max_sessions_per_user);
  double objects = 0, triangles = 0;
  for (int i = 0; i < status.num_sessions; ++i) {
    objects += status.session_objects[i];
    triangles += static_cast<double>(status.session_triangles[i]);
  }
  out.Gauge("far_scene_objects", "objects alive in all sessions' scenes together", objects);
  out.Gauge("far_scene_triangles", "triangles in all sessions' scenes together", triangles);
  AddStepFamilies(status, extras, out);
  // Errors.
  const std::string errors_help = "error replies and dropped messages since start, by kind";
  out.Declare("far_errors_total", errors_help, MetricType::Counter);
  for (int i = 0; i < status.num_error_kinds; ++i) {
    out.Counter("far_errors_total", errors_help, static_cast<double>(status.error_count[i]),
                {{"kind", status.error_kind[i]}});
  }
  out.Counter("far_rejected_messages_total",
              "messages dropped unanswered before they reached a session (undecodable, not "
              "authenticated, replayed, for no session); also counted in far_errors_total",
              static_cast<double>(status.rejected_messages_total));
  return out.Take();
}

}  // namespace far::server
