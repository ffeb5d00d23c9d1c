// far-daemon's GPU cost cache (server/src/gpu_cost_cache.h): what one start keeps, the next
// reads back exactly, under its own key only and while it is fresh; a file that is not a cache
// is an error to warn about and is replaced, never trusted.
#include "gpu_cost_cache.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace far::server {
namespace {

constexpr int64_t kNow = 1'800'000'000;

class GpuCostCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ =
        std::filesystem::temp_directory_path() / ("far-gpu-cost-test-" + std::to_string(getpid()));
    std::filesystem::remove_all(directory_);
    path_ = (directory_ / "cache" / "gpu-costs.json").string();
  }
  void TearDown() override {
    std::filesystem::permissions(directory_, std::filesystem::perms::owner_all,
                                 std::filesystem::perm_options::add);
    std::filesystem::remove_all(directory_);
  }
  void WriteFile(const std::string& text) {
    std::filesystem::create_directories(std::filesystem::path(path_).parent_path());
    std::ofstream(path_, std::ios::binary) << text;
  }
  std::string ReadFile() const {
    std::ifstream file(path_);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }
  std::filesystem::path directory_;
  std::string path_;
};

GpuCost SomeCost() {
  // Values with no short decimal form: kept and read back bit for bit.
  GpuCost cost{1.0 / 3.0, 2.5e-5 / 7.0};
  cost.compute_fixed_ms = 0.1 + 0.2;
  cost.compute_ms_per_triangle = 1e-7 / 3.0;
  return cost;
}

TEST_F(GpuCostCacheTest, AKeptCostIsReadBackExactlyUnderItsKeyOnly) {
  const std::string key = GpuCostKey("llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 Mesa 22.3.6");
  auto missing = ReadCachedGpuCost(path_, key, kNow);
  ASSERT_TRUE(missing.ok()) << missing.error().message;
  EXPECT_FALSE(*missing) << "no file: nothing kept, and not an error";

  ASSERT_TRUE(WriteCachedGpuCost(path_, key, SomeCost(), kNow).ok()) << "its directory is made";
  auto read = ReadCachedGpuCost(path_, key, kNow + 60);
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_TRUE(*read);
  EXPECT_EQ(**read, SomeCost());

  // Another renderer, or another driver of the same one, has nothing kept.
  for (const std::string& other :
       {GpuCostKey("NVIDIA H100 80GB HBM3/PCIe/SSE2", "4.5 Mesa 22.3.6"),
        GpuCostKey("llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 Mesa 23.0.0")}) {
    auto none = ReadCachedGpuCost(path_, other, kNow);
    ASSERT_TRUE(none.ok());
    EXPECT_FALSE(*none) << other;
  }
  EXPECT_NE(key.find("far "), std::string::npos) << key;
  EXPECT_NE(key.find(" build "), std::string::npos) << key;
  EXPECT_NE(key.find("cpus "), std::string::npos) << key;
}

TEST_F(GpuCostCacheTest, EachKeyKeepsItsOwnCostAndACostWithoutTheGpuMethodStaysWithout) {
  GpuCost raster_only{4.0, 0.001};
  ASSERT_TRUE(WriteCachedGpuCost(path_, "a", SomeCost(), kNow).ok());
  ASSERT_TRUE(WriteCachedGpuCost(path_, "b", raster_only, kNow).ok());
  ASSERT_TRUE(WriteCachedGpuCost(path_, "a", SomeCost(), kNow + 1).ok()) << "rewritten in place";
  auto a = ReadCachedGpuCost(path_, "a", kNow + 1);
  auto b = ReadCachedGpuCost(path_, "b", kNow + 1);
  ASSERT_TRUE(a.ok() && *a && b.ok() && *b);
  EXPECT_EQ(**a, SomeCost());
  EXPECT_EQ(**b, raster_only);
  EXPECT_FALSE((*b)->compute_fixed_ms);
  EXPECT_EQ(nlohmann::json::parse(ReadFile())["costs"].size(), 2u);
}

TEST_F(GpuCostCacheTest, ACostOlderThanItsLimitOrFromTheFutureIsMeasuredAgain) {
  ASSERT_TRUE(WriteCachedGpuCost(path_, "k", SomeCost(), kNow).ok());
  auto fresh = ReadCachedGpuCost(path_, "k", kNow + kGpuCostMaxAgeSeconds);
  ASSERT_TRUE(fresh.ok() && *fresh);
  for (int64_t now : {kNow + kGpuCostMaxAgeSeconds + 1, kNow - 1}) {
    auto stale = ReadCachedGpuCost(path_, "k", now);
    ASSERT_TRUE(stale.ok());
    EXPECT_FALSE(*stale) << now;
  }
}

TEST_F(GpuCostCacheTest, AFileThatIsNotACacheIsAnErrorAndIsReplacedWhenWritten) {
  const std::pair<std::string, ErrorCode> cases[] = {
      {"", ErrorCode::kParseError},
      {"{\"format\": \"far-gpu-costs/1\", \"costs\": ", ErrorCode::kParseError},
      {"[1, 2, 3]", ErrorCode::kParseError},
      {"{\"format\": \"far-gpu-costs/2\", \"costs\": {}}", ErrorCode::kParseError},
      {"{\"format\": 1, \"costs\": {}}", ErrorCode::kParseError},
      {"{\"format\": \"far-gpu-costs/1\"}", ErrorCode::kParseError},
      {"\"far-gpu-costs/1\"", ErrorCode::kParseError},
      {"{\"format\": \"far-gpu-costs/1\", \"costs\": []}", ErrorCode::kParseError},
      {std::string(3 << 20, ' ') + "{}", ErrorCode::kIoError},
  };
  for (const auto& [text, code] : cases) {
    WriteFile(text);
    auto read = ReadCachedGpuCost(path_, "k", kNow);
    ASSERT_FALSE(read.ok()) << text.substr(0, 60);
    EXPECT_EQ(read.error().code, code) << read.error().message;
    EXPECT_NE(read.error().message.find(path_), std::string::npos) << read.error().message;
    ASSERT_TRUE(WriteCachedGpuCost(path_, "k", SomeCost(), kNow).ok());
    auto again = ReadCachedGpuCost(path_, "k", kNow);
    ASSERT_TRUE(again.ok() && *again) << "replaced by a valid cache";
  }
}

TEST_F(GpuCostCacheTest, AnEntryWithACostOutOfRangeIsAnErrorNotACost) {
  const char* entries[] = {
      R"({"measured_unix_s": 1800000000, "fixed_ms": -1, "ms_per_triangle": 0})",
      R"({"measured_unix_s": 1800000000, "fixed_ms": 1e300, "ms_per_triangle": 0})",
      R"({"measured_unix_s": 1800000000, "fixed_ms": "1", "ms_per_triangle": 0})",
      R"({"measured_unix_s": 1800000000, "ms_per_triangle": 0})",
      R"({"measured_unix_s": 1800000000, "fixed_ms": 1, "ms_per_triangle": 0,
          "compute_fixed_ms": 2})",
      R"({"measured_unix_s": 1800000000, "fixed_ms": 1, "ms_per_triangle": 0,
          "compute_fixed_ms": 2, "compute_ms_per_triangle": null})",
      R"(17)",
  };
  for (const char* entry : entries) {
    WriteFile(std::string(R"({"format": "far-gpu-costs/1", "costs": {"k": )") + entry + "}}");
    auto read = ReadCachedGpuCost(path_, "k", kNow);
    ASSERT_FALSE(read.ok()) << entry;
    EXPECT_EQ(read.error().code, ErrorCode::kParseError) << entry;
    // Another key's bad entry is not this key's business, and is dropped at the next write.
    auto other = ReadCachedGpuCost(path_, "other", kNow);
    ASSERT_TRUE(other.ok() && !*other) << entry;
    ASSERT_TRUE(WriteCachedGpuCost(path_, "other", SomeCost(), kNow).ok());
    EXPECT_FALSE(nlohmann::json::parse(ReadFile())["costs"].contains("k")) << entry;
  }
}

TEST_F(GpuCostCacheTest, TheFileKeepsTheNewestThirtyTwoKeys) {
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(WriteCachedGpuCost(path_, "key " + std::to_string(i), SomeCost(), kNow + i).ok());
  }
  const nlohmann::json costs = nlohmann::json::parse(ReadFile())["costs"];
  EXPECT_EQ(costs.size(), 32u);
  EXPECT_FALSE(costs.contains("key 7"));
  EXPECT_TRUE(costs.contains("key 8"));
  EXPECT_TRUE(costs.contains("key 39"));
}

TEST_F(GpuCostCacheTest, APathThatCannotHoldTheFileIsAnIoError) {
  // A directory where the file should be.
  std::filesystem::create_directories(path_);
  auto read = ReadCachedGpuCost(path_, "k", kNow);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.error().code, ErrorCode::kIoError);
  auto written = WriteCachedGpuCost(path_, "k", SomeCost(), kNow);
  ASSERT_FALSE(written.ok());
  EXPECT_EQ(written.error().code, ErrorCode::kIoError);
  // A directory that cannot be written (root may write anywhere: nothing to check then).
  if (geteuid() == 0) return;
  const std::string locked = (directory_ / "locked" / "gpu-costs.json").string();
  std::filesystem::create_directories(directory_ / "locked");
  std::filesystem::permissions(directory_ / "locked", std::filesystem::perms::owner_read |
                                                          std::filesystem::perms::owner_exec);
  written = WriteCachedGpuCost(locked, "k", SomeCost(), kNow);
  ASSERT_FALSE(written.ok());
  EXPECT_NE(written.error().message.find(locked), std::string::npos) << written.error().message;
  std::filesystem::permissions(directory_ / "locked", std::filesystem::perms::owner_all);
}

TEST(GpuCostCachePathTest, TheDefaultFollowsXdgThenHomeAndOffHasNone) {
  const char* saved_xdg = std::getenv("XDG_CACHE_HOME");
  const char* saved_home = std::getenv("HOME");
  const std::string xdg = saved_xdg ? saved_xdg : "", home = saved_home ? saved_home : "";
  setenv("XDG_CACHE_HOME", "/var/cache/far", 1);
  setenv("HOME", "/home/sim", 1);
  EXPECT_EQ(GpuCostCachePathOf(""), "/var/cache/far/far/gpu-costs.json");
  EXPECT_EQ(GpuCostCachePathOf("default"), "/var/cache/far/far/gpu-costs.json");
  unsetenv("XDG_CACHE_HOME");
  EXPECT_EQ(GpuCostCachePathOf(""), "/home/sim/.cache/far/gpu-costs.json");
  setenv("XDG_CACHE_HOME", "relative", 1);  // the XDG spec: relative paths are ignored
  EXPECT_EQ(GpuCostCachePathOf(""), "/home/sim/.cache/far/gpu-costs.json");
  unsetenv("XDG_CACHE_HOME");
  unsetenv("HOME");
  EXPECT_EQ(GpuCostCachePathOf(""), "");
  EXPECT_EQ(GpuCostCachePathOf("off"), "");
  EXPECT_EQ(GpuCostCachePathOf("/srv/far/costs.json"), "/srv/far/costs.json");
  if (saved_xdg) setenv("XDG_CACHE_HOME", xdg.c_str(), 1);
  if (saved_home) setenv("HOME", home.c_str(), 1);
}

}  // namespace
}  // namespace far::server
