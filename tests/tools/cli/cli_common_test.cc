// What the tools share: durations need a unit, a file to write is checked without harm, and a
// command line that names no known command says which word it took for one.
#include "cli_common.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace far::cli {
namespace {

TEST(ParseDurationTest, TakesEachUnit) {
  EXPECT_EQ(ParseDuration("--timeout", "500ms")->count(), 500);
  EXPECT_EQ(ParseDuration("--timeout", "60s")->count(), 60'000);
  EXPECT_EQ(ParseDuration("--timeout", "2min")->count(), 120'000);
  EXPECT_EQ(ParseDuration("--timeout", "2m")->count(), 120'000);
  EXPECT_EQ(ParseDuration("--timeout", "0.5s")->count(), 500);
}

TEST(ParseDurationTest, RefusesANumberWithoutAUnitNamingTheUnits) {
  const auto parsed = ParseDuration("--timeout", "5");
  ASSERT_FALSE(parsed.ok());
  EXPECT_EQ(parsed.error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(parsed.error().message, "--timeout: '5' has no unit: write 5ms, 5s or 5min");
}

TEST(ParseDurationTest, RefusesUnknownUnitsAndOutOfRangeValues) {
  for (const char* text : {"5h", "s", "", "-1s", "0ms", "25h", "1e400s", "nan s"}) {
    SCOPED_TRACE(text);
    const auto parsed = ParseDuration("--connect-timeout", text);
    ASSERT_FALSE(parsed.ok());
    EXPECT_NE(parsed.error().message.find("--connect-timeout: '"), std::string::npos)
        << parsed.error().message;
  }
}

class CheckWritableFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("far_cli_common_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(CheckWritableFileTest, LeavesNoFileBehindAndAnExistingOneAsItWas) {
  const std::filesystem::path fresh = dir_ / "fresh.png";
  EXPECT_TRUE(CheckWritableFile("--png", fresh.string()).ok());
  EXPECT_FALSE(std::filesystem::exists(fresh));
  const std::filesystem::path kept = dir_ / "kept.png";
  std::ofstream(kept) << "old picture";
  EXPECT_TRUE(CheckWritableFile("--png", kept.string()).ok());
  std::ifstream in(kept);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "old picture");
}

TEST_F(CheckWritableFileTest, NamesTheFlagAndThePathItCannotWrite) {
  std::ofstream(dir_ / "file") << "";
  const std::string under_file = (dir_ / "file" / "x.png").string();
  const auto refused = CheckWritableFile("--png", under_file);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kIoError);
  EXPECT_EQ(refused.error().message, "--png: " + under_file + ": cannot write: Not a directory");
  const auto folder = CheckWritableFile("--png", dir_.string());
  ASSERT_FALSE(folder.ok());
  EXPECT_EQ(folder.error().message, "--png: " + dir_.string() + ": is a directory, not a file");
}

// A program with two commands, one hidden, as far-client has them.
struct TwoCommands {
  CLI::App app{"test", "far-test"};
  TwoCommands() {
    app.require_subcommand(1);
    app.add_subcommand("ping", "ping");
    app.add_subcommand("play", "play");
    app.add_subcommand("old", "moved")->group("");
  }
};

TEST(ParseCommandLineTest, NamesAnUnknownCommandAndListsTheVisibleOnes) {
  SetProgramName("far-test");
  TwoCommands program;
  ::testing::internal::CaptureStderr();
  const std::optional<int> done = ParseCommandLine(program.app, {"far-test", "bogus"});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(done, kExitUsage);
  EXPECT_EQ(err, "far-test: 'bogus' is not a command; the commands are: ping, play\n");
}

TEST(ParseCommandLineTest, SaysACommandIsRequiredWhenNoneIsGiven) {
  SetProgramName("far-test");
  TwoCommands program;
  ::testing::internal::CaptureStderr();
  const std::optional<int> done = ParseCommandLine(program.app, {"far-test"});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(done, kExitUsage);
  EXPECT_EQ(err, "far-test: a command is required: ping, play (far-test --help)\n");
}

TEST(ParseCommandLineTest, GoesOnAfterAKnownCommand) {
  TwoCommands program;
  EXPECT_EQ(ParseCommandLine(program.app, {"far-test", "play"}), std::nullopt);
}

}  // namespace
}  // namespace far::cli
