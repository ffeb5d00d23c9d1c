#include "metrics.h"

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "atomic_file.h"
#include "metrics_export.h"
#include <gtest/gtest.h>

namespace far::server {
namespace {

using prometheus::ClientMetric;
using prometheus::MetricFamily;
using prometheus::MetricType;

// A status as root sees it: two sessions, two kinds of error.
far_lcm::status_reply_t SampleStatus() {
  far_lcm::status_reply_t status{};
  status.daemon_version = "0.1.0";
  status.daemon_name = "gpu1";
  status.gl_renderer = R"(NVIDIA "H100")";  // quotes: escaped in the text
  status.gl_device = "EGL device 1";
  status.uptime_ms = 12'345;
  status.max_sessions = 64;
  status.max_sessions_per_user = 16;
  status.sessions_open = 2;
  status.steps_total = 1000;
  status.errors_total = 7;
  status.rejected_messages_total = 2;
  status.latency_p50_ms = 1.5;
  status.latency_p90_ms = 3;
  status.latency_p99_ms = 9.25;
  status.latency_max_ms = 40;
  status.latency_samples = 1000;
  status.num_sessions = 2;
  status.session_id = {1, 2};
  status.session_uid = {0, 1000};
  status.session_client_name = {"sim-a", "sim-b"};
  status.session_steps = {600, 400};
  status.session_objects = {10, 5};
  status.session_triangles = {2000, 3000};
  status.session_latency_p50_ms = {1, 2};
  status.session_latency_p99_ms = {5, 9};
  status.num_error_kinds = 2;
  status.error_kind = {"busy", "parse_error"};
  status.error_count = {5, 2};
  status.daemon_pid = 4242;
  status.opens_refused_total = 3;
  status.memory_rss_bytes = 123'456'789;
  status.segment_bytes = 2 * 84'938'752;
  status.num_gpu_names = 2;
  status.gpu_name = {"1", "GPU-8f2c"};
  status.num_methods = 3;
  status.method_name = {"bvh", "far", "gpu"};
  status.method_steps = {700, 200, 100};
  status.session_pid = {100, 200};
  return status;
}

const MetricFamily& Find(const std::vector<MetricFamily>& families, const std::string& name) {
  for (const auto& family : families) {
    if (family.name == name) return family;
  }
  throw std::runtime_error("no family " + name);
}

std::string Label(const ClientMetric& metric, const std::string& name) {
  for (const auto& label : metric.label) {
    if (label.name == name) return label.value;
  }
  return "<none>";
}

TEST(MetricFamiliesTest, EveryFamilyHasHelpATypeAndTheDaemonLabelOnEverySample) {
  const auto families = MetricFamilies(SampleStatus(), {1000, 2500, true});
  std::map<std::string, int> seen;
  for (const auto& family : families) {
    EXPECT_EQ(family.name.rfind("far_", 0), 0u) << family.name;
    EXPECT_FALSE(family.help.empty()) << family.name;
    EXPECT_NE(family.type, MetricType::Untyped) << family.name;
    // Counters, and only counters, end in _total.
    const bool total =
        family.name.size() > 6 && family.name.compare(family.name.size() - 6, 6, "_total") == 0;
    EXPECT_EQ(total, family.type == MetricType::Counter) << family.name;
    EXPECT_EQ(seen[family.name]++, 0) << "family listed twice: " << family.name;
    for (const auto& metric : family.metric) EXPECT_EQ(Label(metric, "daemon"), "gpu1");
  }
  for (const char* name :
       {"far_up", "far_info", "far_uptime_seconds", "far_sessions_open", "far_sessions_max",
        "far_sessions_max_per_user", "far_scene_objects", "far_scene_triangles", "far_steps_total",
        "far_step_latency_seconds", "far_errors_total", "far_rejected_messages_total",
        "far_gpu_info", "far_memory_rss_bytes", "far_segment_bytes", "far_opens_refused_total",
        "far_steps_by_method_total", "far_gpu_batched_steps_total", "far_gpu_batches_total"}) {
    EXPECT_EQ(seen.count(name), 1u) << name;
  }
}

TEST(MetricFamiliesTest, ValuesAreTheStatusInBaseUnits) {
  const auto families = MetricFamilies(SampleStatus(), {1000, 2500, true, 96, 10});
  EXPECT_EQ(Find(families, "far_up").metric.at(0).gauge.value, 1);
  EXPECT_EQ(Find(families, "far_gpu_batched_steps_total").metric.at(0).counter.value, 96);
  EXPECT_EQ(Find(families, "far_gpu_batches_total").metric.at(0).counter.value, 10);
  const ClientMetric& info = Find(families, "far_info").metric.at(0);
  EXPECT_EQ(Label(info, "version"), "0.1.0");
  EXPECT_EQ(Label(info, "gl_renderer"), R"(NVIDIA "H100")");
  EXPECT_EQ(Label(info, "gl_device"), "EGL device 1");
  EXPECT_EQ(Label(info, "pid"), "4242");
  const MetricFamily& gpus = Find(families, "far_gpu_info");
  ASSERT_EQ(gpus.metric.size(), 2u);
  EXPECT_EQ(Label(gpus.metric[0], "gpu"), "1");
  EXPECT_EQ(Label(gpus.metric[1], "gpu"), "GPU-8f2c");
  EXPECT_EQ(gpus.metric[1].gauge.value, 1);
  EXPECT_EQ(Find(families, "far_memory_rss_bytes").metric.at(0).gauge.value, 123'456'789);
  EXPECT_EQ(Find(families, "far_segment_bytes").metric.at(0).gauge.value, 2 * 84'938'752);
  EXPECT_EQ(Find(families, "far_opens_refused_total").metric.at(0).counter.value, 3);
  // Steps by the method that ran, and where it ran: the raster methods and gpu need the GPU.
  const MetricFamily& methods = Find(families, "far_steps_by_method_total");
  ASSERT_EQ(methods.metric.size(), 3u);
  const std::string devices[] = {"cpu", "gpu", "gpu"};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(Label(methods.metric[i], "method"), SampleStatus().method_name[i]);
    EXPECT_EQ(Label(methods.metric[i], "device"), devices[i]) << i;
    EXPECT_EQ(methods.metric[i].counter.value, SampleStatus().method_steps[i]);
  }
  EXPECT_DOUBLE_EQ(Find(families, "far_uptime_seconds").metric.at(0).gauge.value, 12.345);
  EXPECT_EQ(Find(families, "far_sessions_open").metric.at(0).gauge.value, 2);
  EXPECT_EQ(Find(families, "far_sessions_max").metric.at(0).gauge.value, 64);
  EXPECT_EQ(Find(families, "far_sessions_max_per_user").metric.at(0).gauge.value, 16);
  EXPECT_EQ(Find(families, "far_scene_objects").metric.at(0).gauge.value, 15);
  EXPECT_EQ(Find(families, "far_scene_triangles").metric.at(0).gauge.value, 5000);
  EXPECT_EQ(Find(families, "far_steps_total").metric.at(0).counter.value, 1000);
  EXPECT_EQ(Find(families, "far_rejected_messages_total").metric.at(0).counter.value, 2);

  const ClientMetric::Summary& latency =
      Find(families, "far_step_latency_seconds").metric.at(0).summary;
  EXPECT_EQ(latency.sample_count, 1000u);
  EXPECT_DOUBLE_EQ(latency.sample_sum, 2.5);
  ASSERT_EQ(latency.quantile.size(), 4u);
  const double quantiles[] = {0.5, 0.9, 0.99, 1.0};
  const double seconds[] = {0.0015, 0.003, 0.00925, 0.04};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(latency.quantile[i].quantile, quantiles[i]);
    EXPECT_DOUBLE_EQ(latency.quantile[i].value, seconds[i]);
  }

  const MetricFamily& errors = Find(families, "far_errors_total");
  ASSERT_EQ(errors.metric.size(), 2u);
  EXPECT_EQ(Label(errors.metric[0], "kind"), "busy");
  EXPECT_EQ(errors.metric[0].counter.value, 5);
  EXPECT_EQ(Label(errors.metric[1], "kind"), "parse_error");
  EXPECT_EQ(errors.metric[1].counter.value, 2);
}

TEST(MetricFamiliesTest, ShowNoClientNameNorAnyOneSessionsScene) {
  // A user's client names and scene sizes are theirs (status_reply.h); the metrics leave the
  // host (node_exporter serves them to the network).
  const std::string text = MetricsText(MetricFamilies(SampleStatus(), {1000, 2500, true}));
  EXPECT_EQ(text.find("sim-a"), std::string::npos) << text;
  EXPECT_EQ(text.find("sim-b"), std::string::npos);
  EXPECT_EQ(text.find("2000"), std::string::npos);
}

TEST(MetricFamiliesTest, TheLastFileOfACleanStopSaysDown) {
  const auto families = MetricFamilies(SampleStatus(), {1000, 2500, /*up=*/false});
  EXPECT_EQ(Find(families, "far_up").metric.at(0).gauge.value, 0);
}

TEST(MetricFamiliesTest, ADaemonWithoutErrorsStillDeclaresTheErrorCounter) {
  far_lcm::status_reply_t status = SampleStatus();
  status.num_error_kinds = 0;
  status.error_kind.clear();
  status.error_count.clear();
  const std::string text = MetricsText(MetricFamilies(status, {}));
  EXPECT_NE(text.find("# TYPE far_errors_total counter\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("far_errors_total{"), std::string::npos) << text;
}

TEST(MetricsTextTest, IsPrometheusTextWithEscapedLabels) {
  const std::string text = MetricsText(MetricFamilies(SampleStatus(), {1000, 2500, true}));
  for (const char* line : {
           "# TYPE far_steps_total counter\n",
           "far_steps_total{daemon=\"gpu1\"} 1000\n",
           "# TYPE far_step_latency_seconds summary\n",
           "far_step_latency_seconds_count{daemon=\"gpu1\"} 1000\n",
           "far_step_latency_seconds_sum{daemon=\"gpu1\"} 2.5\n",
           "far_step_latency_seconds{daemon=\"gpu1\",quantile=\"0.99\"} 0.00925\n",
           "far_errors_total{daemon=\"gpu1\",kind=\"busy\"} 5\n",
           "far_steps_by_method_total{daemon=\"gpu1\",method=\"far\",device=\"gpu\"} 200\n",
           "far_memory_rss_bytes{daemon=\"gpu1\"} 123456789\n",
           "gl_renderer=\"NVIDIA \\\"H100\\\"\"",
       }) {
    EXPECT_NE(text.find(line), std::string::npos) << line << "\nin:\n" << text;
  }
}

class WriteFileAtomicallyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ =
        std::filesystem::temp_directory_path() / ("far-metrics-test-" + std::to_string(getpid()));
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }
  std::filesystem::path directory_;
};

TEST_F(WriteFileAtomicallyTest, ReplacesTheFileReadableByAllAndLeavesNoTemporaryFile) {
  const std::string path = (directory_ / "far.prom").string();
  ASSERT_TRUE(WriteFileAtomically(path, "first\n").ok());
  ASSERT_TRUE(WriteFileAtomically(path, "second\n").ok());
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_EQ(text.str(), "second\n");
  struct stat info {};
  ASSERT_EQ(stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0644u);
  int entries = 0;
  for (const auto& entry : std::filesystem::directory_iterator(directory_)) {
    ++entries;
    EXPECT_EQ(entry.path().filename(), "far.prom");
  }
  EXPECT_EQ(entries, 1);
}

TEST_F(WriteFileAtomicallyTest, AMissingDirectoryIsAnIoErrorNamingThePath) {
  const std::string path = (directory_ / "gone" / "far.prom").string();
  auto written = WriteFileAtomically(path, "x\n");
  ASSERT_FALSE(written.ok());
  EXPECT_EQ(written.error().code, ErrorCode::kIoError);
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
}

}  // namespace
}  // namespace far::server
