#include "daemon_config.h"

#include <filesystem>
#include <fstream>

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
      "max_sessions": 3, "log_level": "debug", "lcm_url": "memq://"})"));
  ASSERT_TRUE(config.ok()) << ToString(config.error());
  EXPECT_EQ(config->max_resolution, 512);
  EXPECT_EQ(config->gl_platform, GlPlatform::kSurfaceless);
  EXPECT_EQ(config->max_sessions, 3);
  EXPECT_EQ(config->lcm_url, "memq://");
}

TEST(DaemonConfigTest, RejectsUnknownKeysWrongTypesAndRanges) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"max_sesions": 3})", "max_sesions"},
      {R"({"max_sessions": "three"})", "wrong type"},
      {R"({"max_resolution": 4})", "max_resolution"},
      {R"({"default_resolution": 512})", "default_resolution"},
      {R"({"ring_bytes": 100000})", "ring_bytes"},
      {R"({"log_level": "loud"})", "log_level"},
      {R"({"depth_format": "depth8"})", "depth_format"},
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

}  // namespace
}  // namespace far::server
