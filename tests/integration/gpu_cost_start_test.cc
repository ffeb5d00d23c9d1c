// far-daemon keeps auto's GPU cost between starts (docs/daemon.md, "The GPU cost at
// start-up"): the first start on a renderer measures it and writes the cache file, the next
// reads it instead of spending seconds rendering the probe's scenes; "off" always measures;
// a file that is not a cache is reported, measured over and replaced.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "daemon_process.h"
#include <gtest/gtest.h>

namespace far::integration {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const fs::path& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// Starts a daemon with `args`, stops it, and returns its log.
std::string LogOfAStart(std::vector<std::string> args) {
  DaemonProcess daemon(std::move(args));
  auto started = daemon.Start();
  EXPECT_TRUE(started.ok()) << started.error().message;
  auto stopped = daemon.Stop();
  EXPECT_TRUE(stopped.ok() && *stopped == 0) << daemon.Log();
  return daemon.Log();
}

// The cost the log's event=gpu_cost line gives ("fixed_ms=... ms_per_triangle=..."), from
// `source` ("measured" or "cached"); "" when there is no such line.
std::string LoggedCost(const std::string& log, const std::string& source) {
  const std::string start = "event=gpu_cost source=" + source + " ";
  const size_t at = log.find(start);
  if (at == std::string::npos) return "";
  const size_t fields = log.find("fixed_ms=", at);
  return log.substr(fields, log.find('\n', fields) - fields);
}

TEST(GpuCostStartTest, ASecondStartReadsTheCostTheFirstMeasuredAndOffAlwaysMeasures) {
  TempDir dir;
  const fs::path path = dir.path() / "cache" / "gpu-costs.json";
  const std::string first = LogOfAStart({"--gpu-cost-cache", path.string()});
  const std::string measured = LoggedCost(first, "measured");
  ASSERT_NE(measured, "") << first;
  EXPECT_NE(first.find("gpu_cost=measured"), std::string::npos) << "in daemon_ready:\n" << first;
  ASSERT_TRUE(fs::exists(path)) << "the file and its directory are made";
  const std::string kept = ReadText(path);
  EXPECT_NE(kept.find("\"format\": \"far-gpu-costs/1\""), std::string::npos) << kept;

  const std::string second = LogOfAStart({"--gpu-cost-cache", path.string()});
  EXPECT_EQ(LoggedCost(second, "cached"), measured) << second;
  EXPECT_NE(second.find("gpu_cost=cached"), std::string::npos) << second;
  EXPECT_EQ(second.find("source=measured"), std::string::npos) << "not measured again";

  const std::string off = LogOfAStart({"--gpu-cost-cache", "off"});
  EXPECT_NE(LoggedCost(off, "measured"), "") << off;
  EXPECT_EQ(ReadText(path), kept) << "off neither reads nor writes a file";
}

TEST(GpuCostStartTest, AFileThatIsNotACacheIsMeasuredOverAndTheDefaultFileIsUnderXdgCacheHome) {
  TempDir dir;
  const fs::path path = dir.path() / "gpu-costs.json";
  std::ofstream(path) << "{\"format\": \"something else\"}";
  const std::string log = LogOfAStart({"--gpu-cost-cache", path.string()});
  EXPECT_NE(log.find("event=gpu_cost_cache_unreadable"), std::string::npos) << log;
  EXPECT_NE(log.find(path.string()), std::string::npos) << "the warning names the file:\n" << log;
  const std::string measured = LoggedCost(log, "measured");
  ASSERT_NE(measured, "") << log;
  const std::string replaced = ReadText(path);
  ASSERT_NE(replaced.find("far-gpu-costs/1"), std::string::npos) << replaced;

  // By default (what a daemon without --gpu-cost-cache does), the file is
  // $XDG_CACHE_HOME/far/gpu-costs.json: there, the file just written is read.
  const fs::path xdg = dir.path() / "xdg";
  fs::create_directories(xdg / "far");
  fs::copy_file(path, xdg / "far" / "gpu-costs.json");
  const char* saved = std::getenv("XDG_CACHE_HOME");
  const std::optional<std::string> old = saved ? std::optional<std::string>(saved) : std::nullopt;
  setenv("XDG_CACHE_HOME", xdg.c_str(), 1);
  const std::string by_default = LogOfAStart({"--gpu-cost-cache", "default"});
  if (old) {
    setenv("XDG_CACHE_HOME", old->c_str(), 1);
  } else {
    unsetenv("XDG_CACHE_HOME");
  }
  EXPECT_EQ(LoggedCost(by_default, "cached"), measured) << by_default;
  EXPECT_NE(by_default.find((xdg / "far" / "gpu-costs.json").string()), std::string::npos)
      << by_default;
}

}  // namespace
}  // namespace far::integration
