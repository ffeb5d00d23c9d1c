// far::GpuIdentifiers on made-up sysfs and procfs trees: what NVIDIA's driver and the kernel
// publish for a GPU, and what they publish for devices that are not NVIDIA's or not there.
#include "far/base/gpu_identity.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace far {
namespace {

namespace fs = std::filesystem;

class GpuIdentityTest : public ::testing::Test {
 protected:
  GpuIdentityTest() {
    root_ = fs::temp_directory_path() / ("far-gpu-identity-" + std::to_string(getpid()));
    fs::create_directories(root_ / "sys/class/drm");
    fs::create_directories(root_ / "sys/devices/pci0000:00");
  }
  ~GpuIdentityTest() override { fs::remove_all(root_); }

  // /sys/class/drm/<card>/device -> ../../../devices/pci0000:00/<pci>, as the kernel links it.
  void AddCard(const std::string& card, const std::string& pci) {
    fs::create_directories(root_ / "sys/devices/pci0000:00" / pci);
    fs::create_directories(root_ / "sys/class/drm" / card);
    fs::create_symlink("../../../devices/pci0000:00/" + pci,
                       root_ / "sys/class/drm" / card / "device");
  }
  // /proc/driver/nvidia/gpus/<pci>/information, as NVIDIA's driver writes it.
  void AddNvidiaInformation(const std::string& pci, int minor, const std::string& uuid) {
    const fs::path dir = root_ / "proc/driver/nvidia/gpus" / pci;
    fs::create_directories(dir);
    std::ofstream(dir / "information") << "Model: \t\t NVIDIA H100 80GB HBM3\n"
                                       << "IRQ:   \t\t 0\n"
                                       << "GPU UUID: \t " << uuid << "\n"
                                       << "Video BIOS: \t ??.??.??.??.??\n"
                                       << "Bus Type: \t PCIe\n"
                                       << "DMA Size: \t 52 bits\n"
                                       << "Bus Location: \t " << pci << "\n"
                                       << "Device Minor: \t " << minor << "\n"
                                       << "GPU Excluded:\t No\n";
  }
  std::string root() const { return root_.string(); }

  fs::path root_;
};

TEST_F(GpuIdentityTest, AnNvidiaGpuIsNamedByMinorUuidAndPciAddress) {
  AddCard("card1", "0000:3b:00.0");
  AddNvidiaInformation("0000:3b:00.0", 2, "GPU-6f0e2b1c-1a2b-4c3d-8e9f-0123456789ab");
  EXPECT_EQ(
      GpuIdentifiers("/dev/dri/card1", root()),
      (std::vector<std::string>{"2", "GPU-6f0e2b1c-1a2b-4c3d-8e9f-0123456789ab", "0000:3b:00.0"}));
}

TEST_F(GpuIdentityTest, AnotherVendorsGpuHasOnlyItsPciAddress) {
  AddCard("card0", "0000:C1:00.0");
  EXPECT_EQ(GpuIdentifiers("/dev/dri/card0", root()), (std::vector<std::string>{"0000:c1:00.0"}));
}

TEST_F(GpuIdentityTest, NoDrmFileOrAMissingCardHasNoNames) {
  EXPECT_TRUE(GpuIdentifiers("", root()).empty());  // software devices, surfaceless
  EXPECT_TRUE(GpuIdentifiers("/dev/dri/card7", root()).empty());
}

TEST(GpuNamesTest, MatchIgnoringCaseAndAPciDomainLeftOut) {
  const std::vector<std::string> names = {"2", "GPU-6f0e", "0000:3b:00.0"};
  EXPECT_TRUE(NamesGpu("2", names));
  EXPECT_TRUE(NamesGpu("gpu-6F0E", names));
  EXPECT_TRUE(NamesGpu("0000:3B:00.0", names));
  EXPECT_TRUE(NamesGpu("3b:00.0", names));
  EXPECT_TRUE(NamesGpu(" 2 ", names));
  EXPECT_FALSE(NamesGpu("20", names));
  EXPECT_FALSE(NamesGpu("1", names));
  EXPECT_FALSE(NamesGpu("", names));
  EXPECT_FALSE(NamesGpu("GPU-6f0e2", names));
  EXPECT_FALSE(NamesGpu("2", {}));
}

}  // namespace
}  // namespace far
