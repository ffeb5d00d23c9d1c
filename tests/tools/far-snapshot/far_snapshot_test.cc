// far-snapshot writes a PNG of the requested size whose contact-red pixels exist exactly when
// the scene has contacts, with the contacts listed by object name; a frame the scene does not
// have or a PNG it cannot write is refused before any drawing. Label gpu: the step and the
// picture are drawn on llvmpipe (or a GPU), in the far-snapshot process.

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "far/io/png_io.h"
#include "far/io/scene_io.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

// Pixels that are plainly the contact colour (lit or in shade), not grey, yellow, orange or the
// background, nor a faded contact seen through something else.
bool IsContactRed(const uint8_t* p) { return p[0] >= 60 && p[0] > 3 * p[1] && p[0] > 3 * p[2]; }

size_t Count(const std::vector<uint8_t>& rgb, bool (*is)(const uint8_t*)) {
  size_t n = 0;
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) n += is(&rgb[i]) ? 1 : 0;
  return n;
}

// Runs far-snapshot with `args`; returns its exit status and stdout + stderr. The build tree's
// far-snapshot, or $FAR_SNAPSHOT where the test runs elsewhere (deploy/gpu-run.sh, a bundle).
std::pair<int, std::string> RunFarSnapshot(const std::string& args) {
  const char* snapshot = std::getenv("FAR_SNAPSHOT");
  const std::string command =
      std::string(snapshot != nullptr ? snapshot : FAR_SNAPSHOT_PATH) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  std::string out;
  std::array<char, 4096> buffer;
  while (size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// Two named spheres, `gap` apart along x (negative: they interpenetrate), as a scene file.
std::filesystem::path WriteTwoBalls(const std::filesystem::path& dir, double gap) {
  Scene scene;
  for (uint32_t id : {1u, 2u}) {
    SceneObject ball;
    ball.id = id;
    ball.name = id == 1 ? "ball-a" : "ball-b";
    ball.motion = Motion::kRigid;
    ball.mesh_path = "ball.obj";
    ball.mesh = scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.5, 8, 16);
    ball.X_WO.translation = Eigen::Vector3d(id == 1 ? 0.0 : 1.0 + gap, 0, 0);
    scene.objects.push_back(ball);
  }
  const std::filesystem::path path = dir / "balls.json";
  EXPECT_TRUE(WriteScene(scene, path).ok());
  return path;
}

class SnapshotCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("far_snapshot_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(SnapshotCommandTest, PngHasTheSizeAndRedPixelsExactlyWhenThereAreContacts) {
  for (const double gap : {-0.3, 1.0}) {
    SCOPED_TRACE("gap " + std::to_string(gap));
    const bool touching = gap < 0;
    const std::filesystem::path scene = WriteTwoBalls(dir_, gap);
    const std::filesystem::path png = dir_ / "balls.png";
    const auto [status, out] = RunFarSnapshot(scene.string() + " --png " + png.string() +
                                              " --width 200 --height 150 --method exact");
    ASSERT_EQ(status, 0) << out;
    auto image = ReadPng(png);
    ASSERT_TRUE(image.ok()) << ToString(image.error());
    EXPECT_EQ(image->width, 200);
    EXPECT_EQ(image->height, 150);
    const size_t red = Count(image->rgb, IsContactRed);
    if (touching) {
      EXPECT_GT(red, 0u) << out;
      // The contacts, by object name; both balls move, so the smaller id comes first.
      EXPECT_NE(out.find("ball-a touches ball-b ("), std::string::npos) << out;
    } else {
      EXPECT_EQ(red, 0u) << out;
      EXPECT_EQ(out.find("touches"), std::string::npos) << out;
      EXPECT_NE(out.find(" 0 contact pairs"), std::string::npos) << out;
    }
    std::filesystem::remove(png);
  }
}

TEST_F(SnapshotCommandTest, RefusesAFrameTheSceneDoesNotHave) {
  const std::filesystem::path scene = WriteTwoBalls(dir_, 1.0);
  const auto [status, out] =
      RunFarSnapshot(scene.string() + " --png " + (dir_ / "x.png").string() + " --frame 3");
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("--frame: step 3: the scene has steps 0..0"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.png"));
}

// A PNG that cannot be written is refused with its path before the step runs, not after it
// was drawn (and never as an abort).
TEST_F(SnapshotCommandTest, RefusesAPngItCannotWriteBeforeTheStep) {
  const std::filesystem::path scene = WriteTwoBalls(dir_, -0.3);
  std::FILE* file = std::fopen((dir_ / "file").c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fclose(file);
  const std::string png = (dir_ / "file" / "x.png").string();
  const auto [status, out] = RunFarSnapshot(scene.string() + " --png " + png);
  EXPECT_EQ(status, 1) << out;
  EXPECT_EQ(out, "far-snapshot: io_error: --png: " + png + ": cannot write: Not a directory\n");
}

// Snapshot runs its step in-process: a --timeout it took would bound nothing, so it has none.
TEST_F(SnapshotCommandTest, HasNoTimeoutOption) {
  const std::filesystem::path scene = WriteTwoBalls(dir_, 1.0);
  const auto [status, out] =
      RunFarSnapshot(scene.string() + " --png " + (dir_ / "x.png").string() + " --timeout 1s");
  EXPECT_NE(status, 0) << out;
  EXPECT_NE(out.find("--timeout"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.png"));
}

}  // namespace
}  // namespace far
