#pragma once

#include <memory>
#include <string>
#include <vector>

#include "far/base/result.h"
#include "far/gpu/gl_platform.h"

namespace far {

/// A headless OpenGL 4.5 core context made with EGL (no X server, no window).
///
/// Threading contract: the context is made current on the thread that calls Create and must only
/// be used (and destroyed) on that thread. Every far class that issues GL calls (the culling
/// renderers, Pipeline) inherits this contract: one GL thread owns them. A process may hold one
/// context per thread; their GL work takes turns under far::LockGl (gl_lock.h).
class GlContext {
 public:
  /// Creates a context and makes it current on the calling thread. Tries, in order (kAuto): EGL
  /// devices that are not software renderers, then software devices, then the surfaceless
  /// platform. kDevice tries the hardware devices only: a software device
  /// (EGL_MESA_device_software) and a device whose GL_RENDERER is Mesa's llvmpipe, softpipe or
  /// swrast are listed as tried, not used. Returns kUnavailable with every attempt and why it
  /// failed listed when none works ("no GPU found through the EGL device platform ..." for
  /// kDevice).
  /// With `device` >= 0, uses EGL device `device` (in ListDevices' order) and nothing else,
  /// whatever `platform` says; kUnavailable when it does not exist or makes no context.
  static Result<std::unique_ptr<GlContext>> Create(GlPlatform platform = GlPlatform::kAuto,
                                                   int device = -1);

  /// An EGL device: its index (Create's `device`), a line naming it ("EGL device 0 (hardware,
  /// /dev/dri/card0)", "EGL device 1 (EGL_MESA_device_software)") and its DRM file ("" when
  /// EGL_EXT_device_drm gives none), which leads to the names a scheduler gives the GPU
  /// (far::GpuIdentifiers).
  struct Device {
    int index = 0;
    std::string description;
    std::string drm_device_file;
  };
  /// The EGL devices in EGL's order. Empty without the EGL device platform.
  static std::vector<Device> ListDevices();

  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)" or "NVIDIA H100 PCIe/PCIe/SSE2".
  const std::string& renderer() const;
  /// GL_VERSION, e.g. "4.5 (Core Profile) Mesa 22.3.6".
  const std::string& version() const;
  /// How the context was made, e.g. "EGL device 0 (EGL_MESA_device_software)" or "surfaceless".
  const std::string& platform_description() const;
  /// The DRM file of the EGL device the context was made on ("/dev/dri/card1"); "" for a
  /// software device or the surfaceless platform.
  const std::string& drm_device_file() const;

 private:
  struct Impl;
  explicit GlContext(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

namespace internal {
/// Whether EGL's client extension string offers the EGL device platform with device
/// enumeration: EGL_EXT_platform_device, and EGL_EXT_device_enumeration or EGL_EXT_device_base
/// (the two device extensions in one; NVIDIA's driver names only that one).
bool OffersEglDevicePlatform(const char* client_extensions);
}  // namespace internal

}  // namespace far
