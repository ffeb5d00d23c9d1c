#include "daemon_config.h"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace far::server {
namespace {

std::filesystem::path WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("far-config-test-" + name + ".json");
  std::ofstream(path) << text;
  return path;
}

TEST(DaemonConfigTest, DefaultsAreValid) { EXPECT_TRUE(ValidateDaemonConfig(DaemonConfig{}).ok()); }

TEST(DaemonConfigTest, ReadsKnownKeys) {
  auto config =
      LoadDaemonConfig(WriteTemp("ok", R"({"max_resolution": 512, "gl_platform": "surfaceless",
      "max_sessions": 3, "log_level": "debug", "lcm_url": "memq://", "setup_allowance_ms": 250,
      "status_after_ms": 0, "gpu_batch": false, "gpu_cost_cache": "off"})"));
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_FALSE(config->gpu_batch);
  EXPECT_TRUE(DaemonConfig{}.gpu_batch);
  EXPECT_EQ(config->gpu_cost_cache, "off");
  EXPECT_EQ(DaemonConfig{}.gpu_cost_cache, "");
  EXPECT_EQ(config->setup_allowance_ms, 250);
  EXPECT_EQ(config->status_after_ms, 0);
  EXPECT_EQ(config->max_resolution, 512);
  EXPECT_EQ(config->gl_platform, GlPlatform::kSurfaceless);
  EXPECT_EQ(config->max_sessions, 3);
  EXPECT_EQ(config->lcm_url, "memq://");
}

TEST(DaemonConfigTest, RejectsUnknownKeysWrongTypesAndRanges) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"max_sesions": 3})", "max_sesions"},
      {R"({"max_sessions": "three"})", "max_sessions"},
      {R"({"log_level": 3})", "wrong type"},
      {R"({"max_resolution": 4})", "max_resolution"},
      {R"({"default_resolution": 512})", "default_resolution"},
      {R"({"ring_bytes": 100000})", "ring_bytes"},
      {R"({"log_level": "loud"})", "log_level"},
      {R"({"depth_format": "depth8"})", "depth_format"},
      {R"({"setup_allowance_ms": -1})", "setup_allowance_ms"},
      {R"({"status_after_ms": -1})", "status_after_ms"},
      {R"({"status_after_ms": 60001})", "status_after_ms"},
      {R"({"gpu_batch": 1})", "'gpu_batch': 1 is not true or false"},
      {R"({"gpu_cost_cache": false})", "wrong type"},
      {R"([1, 2])", "not a JSON object"},
      {R"({"max_sessions": )", ""},
  };
  int i = 0;
  for (const auto& [text, expected] : cases) {
    auto config = LoadDaemonConfig(WriteTemp("bad" + std::to_string(i++), text));
    ASSERT_FALSE(config.ok()) << text;
    EXPECT_NE(config.error().message.find(expected), std::string::npos) << config.error().message;
  }
  EXPECT_EQ(LoadDaemonConfig("/nonexistent/far.json").error().code, ErrorCode::kIoError);
}

TEST(DaemonConfigTest, ReadsTheGpusNamesAndRefusesBadOnesAndTheNameAuto) {
  auto config = ParseDaemonConfig(
      R"({"gpu_id": "GPU-6f0e2b1c", "serves_gpus": ["2", "0000:3b:00.0"]})", "daemon.json");
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->gpu_id, "GPU-6f0e2b1c");
  EXPECT_EQ(config->serves_gpus, (std::vector<std::string>{"2", "0000:3b:00.0"}));
  const std::pair<const char*, const char*> cases[] = {
      {R"({"gpu_id": "2", "gpu": 1})", "not both"},
      {R"({"gpu_id": "two gpus"})", "gpu_id"},
      {R"({"serves_gpus": "2"})", "wrong type"},
      {R"({"serves_gpus": ["2", ""]})", "serves_gpus"},
      {R"({"serves_gpus": ["a,b"]})", "serves_gpus"},
      {R"({"name": "auto"})", "reserved"},
  };
  for (const auto& [text, expected] : cases) {
    auto bad = ParseDaemonConfig(text, "daemon.json");
    ASSERT_FALSE(bad.ok()) << text;
    EXPECT_NE(bad.error().message.find(expected), std::string::npos) << bad.error().message;
  }
}

TEST(DaemonConfigTest, ReadsTheSharedBudgetsAndTheIdleTimeout) {
  auto config = ParseDaemonConfig(
      R"({"session_idle_timeout_s": 30, "max_segment_bytes_total": 1073741824,
      "max_sessions": 8, "max_triangles_total": 1000, "max_vertices_total": 3000})",
      "inline.json");
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->session_idle_timeout_s, 30);
  const BudgetAmounts totals = BudgetTotalsOf(*config);
  EXPECT_EQ(totals[BudgetKind::kSessions], 8);
  EXPECT_EQ(totals[BudgetKind::kSegmentBytes], int64_t{1} << 30);
  EXPECT_EQ(totals[BudgetKind::kTriangles], 1000);
  EXPECT_EQ(totals[BudgetKind::kVertices], 3000);
  // By default: as many bytes as max_sessions segments of the largest rings (and a header page).
  const DaemonConfig defaults;
  EXPECT_EQ(BudgetTotalsOf(defaults)[BudgetKind::kSegmentBytes], 64 * ((int64_t{80} << 20) + 4096));
  EXPECT_EQ(defaults.session_idle_timeout_s, 600);
  for (const char* bad : {R"({"session_idle_timeout_s": 0.5})", R"({"session_idle_timeout_s": -1})",
                          R"({"max_segment_bytes_total": -1})"}) {
    auto refused = ParseDaemonConfig(bad, "inline.json");
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
  }
  EXPECT_TRUE(ParseDaemonConfig(R"({"session_idle_timeout_s": 0})", "inline.json").ok());
}

TEST(DaemonConfigTest, ReadsCpuCoresWithinItsRange) {
  auto config = ParseDaemonConfig(R"({"cpu_cores": 3, "exact_threads": 8})", "inline.json");
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->cpu_cores, 3);
  EXPECT_EQ(CpuCoresOf(*config), 3);
  EXPECT_EQ(config->exact_threads, 8);
  // 0, the default: every core of the machine.
  const DaemonConfig defaults;
  EXPECT_EQ(defaults.cpu_cores, 0);
  EXPECT_EQ(CpuCoresOf(defaults),
            std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  EXPECT_TRUE(ParseDaemonConfig(R"({"cpu_cores": 4096})", "inline.json").ok());
  for (const char* bad : {R"({"cpu_cores": -1})", R"({"cpu_cores": 4097})", R"({"cpu_cores": 1.5})",
                          R"({"cpu_cores": "2"})"}) {
    auto refused = ParseDaemonConfig(bad, "inline.json");
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument) << bad;
    EXPECT_NE(refused.error().message.find("cpu_cores"), std::string::npos)
        << refused.error().message;
  }
}

TEST(DaemonConfigTest, ReadsTheMetricsKeysAndRefusesAFileNodeExporterWouldNotRead) {
  const std::string directory = std::filesystem::temp_directory_path().string();
  auto config = ParseDaemonConfig(R"({"metrics_file": ")" + directory +
                                      R"(/far.prom", "metrics_port": 9464,
      "metrics_interval_s": 1.5})",
                                  "metrics.json");
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->metrics_file, directory + "/far.prom");
  EXPECT_EQ(config->metrics_port, 9464);
  EXPECT_EQ(config->metrics_interval_s, 1.5);
  EXPECT_EQ(DaemonConfig{}.metrics_interval_s, 5);
  const std::pair<std::string, const char*> cases[] = {
      {R"({"metrics_file": "/nonexistent-far-dir/far.prom"})", "does not exist"},
      {R"({"metrics_file": ")" + directory + R"(/far.txt"})", "does not end in .prom"},
      {R"({"metrics_port": 65536})", "metrics_port"},
      {R"({"metrics_port": -1})", "metrics_port"},
      {R"({"metrics_interval_s": 0})", "metrics_interval_s"},
  };
  for (const auto& [text, expected] : cases) {
    auto refused = ParseDaemonConfig(text, "metrics.json");
    ASSERT_FALSE(refused.ok()) << text;
    EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument) << text;
    EXPECT_NE(refused.error().message.find(expected), std::string::npos) << refused.error().message;
  }
}

TEST(DaemonConfigTest, ParsesTextInMemoryWithTheGivenName) {
  auto config = ParseDaemonConfig(R"({"max_sessions": 5})", "inline.json");
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->max_sessions, 5);
  auto bad = ParseDaemonConfig("{", "inline.json");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kParseError);
  EXPECT_EQ(bad.error().message.rfind("inline.json: ", 0), 0u) << bad.error().message;
}

// Found by the daemon_config fuzz target (the first case is its crash input verbatim): nlohmann's
// get<T> casts any JSON number, so a double out of T's range was undefined behaviour (UBSan:
// float-cast-overflow) and an integer out of range or a boolean was silently wrapped or taken.
TEST(DaemonConfigTest, RejectsNumbersOutsideTheFieldsTypeInsteadOfCastingThem) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"ring_bytes":101073749223372036854775807180})", "ring_bytes"},
      {R"({"max_resolution": 1e10})", "max_resolution"},
      {R"({"max_resolution": 512.5})", "max_resolution"},
      {R"({"reply_bytes": -65536})", "reply_bytes"},
      {R"({"max_sessions": 4294967297})", "max_sessions"},
      {R"({"max_sessions": true})", "max_sessions"},
      {R"({"max_triangles_per_session": 9223372036854775808})", "max_triangles_per_session"},
      {R"({"max_requests_per_second": "fast"})", "max_requests_per_second"},
  };
  for (const auto& [text, key] : cases) {
    auto config = ParseDaemonConfig(text, "fuzz.json");
    ASSERT_FALSE(config.ok()) << text;
    EXPECT_EQ(config.error().code, ErrorCode::kInvalidArgument) << text;
    EXPECT_NE(config.error().message.find(std::string("config '") + key + "'"), std::string::npos)
        << config.error().message;
  }
  auto exact = ParseDaemonConfig(
      R"({"max_triangles_per_session": 9223372036854775807, "max_requests_per_second": 1e300})",
      "fuzz.json");
  ASSERT_TRUE(exact.ok()) << ToString(exact.error());
  EXPECT_EQ(exact->max_triangles_per_session, INT64_MAX);
  EXPECT_EQ(exact->max_requests_per_second, 1e300);
}

// Budgets up to INT64_MAX are valid; the limits derived from them must stay in range (a ring
// record never carries more than 2^30 elements).
TEST(DaemonConfigTest, DerivedLimitsOfHugeBudgetsStayInRange) {
  auto huge = ParseDaemonConfig(
      R"({"max_triangles_per_session": 9223372036854775807, "max_vertices_per_session": 7868123033422542130})",
      "fuzz.json");
  ASSERT_TRUE(huge.ok()) << ToString(huge.error());
  EXPECT_EQ(SceneLimitsOf(*huge).max_triangles, INT64_MAX);
  EXPECT_EQ(SceneLimitsOf(*huge).max_vertices, 7868123033422542130);
  EXPECT_EQ(RingLimitsOf(*huge).max_triangles, 1u << 30);
  EXPECT_EQ(RingLimitsOf(*huge).max_vertices, 1u << 30);
  DaemonConfig config;
  config.max_triangles_per_session = 1000;
  config.max_vertices_per_session = 3000;
  EXPECT_EQ(RingLimitsOf(config).max_triangles, 1000u);
  EXPECT_EQ(RingLimitsOf(config).max_vertices, 3000u);
}

}  // namespace
}  // namespace far::server
