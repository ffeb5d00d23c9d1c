#include "far/base/gpu_identity.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <string_view>

namespace far {
namespace {

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string Trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r\n");
  return std::string(text.substr(first, last - first + 1));
}

// A "0000:3b:00.0" PCI address: the domain is optional in what users write.
std::string WithPciDomain(const std::string& id) {
  // bus:device.function, e.g. "3b:00.0": two colons make a full address.
  if (std::count(id.begin(), id.end(), ':') == 1 && id.find('.') != std::string::npos)
    return "0000:" + id;
  return id;
}

}  // namespace

std::vector<std::string> GpuIdentifiers(const std::string& drm_device_file,
                                        const std::string& root) {
  namespace fs = std::filesystem;
  std::vector<std::string> ids;
  if (drm_device_file.empty()) return ids;
  // /dev/dri/card1 -> /sys/class/drm/card1/device -> ../../../0000:3b:00.0
  const std::string card = fs::path(drm_device_file).filename();
  std::error_code error;
  const fs::path device = fs::read_symlink(root + "/sys/class/drm/" + card + "/device", error);
  if (error) return ids;
  const std::string pci = Lower(device.filename());
  if (pci.empty()) return ids;

  // NVIDIA's driver: "Device Minor:   2" and "GPU UUID:   GPU-6f0e..." among other lines.
  std::ifstream information(root + "/proc/driver/nvidia/gpus/" + pci + "/information");
  std::string minor, uuid;
  for (std::string line; std::getline(information, line);) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = Trim(std::string_view(line).substr(0, colon));
    const std::string value = Trim(std::string_view(line).substr(colon + 1));
    if (key == "Device Minor") minor = value;
    if (key == "GPU UUID") uuid = value;
  }
  if (!minor.empty()) ids.push_back(minor);
  if (!uuid.empty()) ids.push_back(uuid);
  ids.push_back(pci);
  return ids;
}

bool NamesGpu(const std::string& id, const std::vector<std::string>& identifiers) {
  const std::string wanted = WithPciDomain(Lower(Trim(id)));
  if (wanted.empty()) return false;
  return std::any_of(identifiers.begin(), identifiers.end(), [&](const std::string& known) {
    return WithPciDomain(Lower(known)) == wanted;
  });
}

}  // namespace far
