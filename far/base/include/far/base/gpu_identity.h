#pragma once

// What a cluster scheduler calls a GPU, read from the files the kernel and NVIDIA's driver
// publish. Slurm's gres indices (SLURM_JOB_GPUS, SLURM_STEP_GPUS) are the N of /dev/nvidiaN
// when gres.conf lists the devices in minor order,
// NVIDIA's Kubernetes device plugin names GPUs by UUID (NVIDIA_VISIBLE_DEVICES), and every
// vendor's device has a PCI address. EGL names none of them, but EGL_EXT_device_drm gives the
// device's DRM file (/dev/dri/cardN), which leads to all three (docs/cluster.md).

#include <string>
#include <vector>

namespace far {

/// The identifiers of the GPU behind DRM device file `drm_device_file` (e.g. "/dev/dri/card1"):
///  - its PCI address, lower case ("0000:3b:00.0"): /sys/class/drm/cardN/device links to it;
///  - for NVIDIA's driver, its device minor number ("2", the N of /dev/nvidiaN) and its UUID
///    ("GPU-6f0e..."), from /proc/driver/nvidia/gpus/<pci address>/information.
/// In that order: minor, UUID, PCI address, those that exist. Empty for an empty file name
/// (software renderers and the surfaceless platform have none) or one that leads nowhere.
/// `root` prefixes every path read (tests point it at a made-up tree).
std::vector<std::string> GpuIdentifiers(const std::string& drm_device_file,
                                        const std::string& root = "");

/// Whether `id` names the same GPU as one of `identifiers`: equal, ignoring case (a PCI address
/// may come in upper case), and a PCI address given without its domain ("3b:00.0") matches
/// domain 0000.
bool NamesGpu(const std::string& id, const std::vector<std::string>& identifiers);

}  // namespace far
