#include "far/gpu/gl_context.h"

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "far/gpu/gl_lock.h"

namespace far {

namespace {

// What a made context holds; GlContext::Impl wraps it.
struct EglState {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string renderer, version, platform;
  std::string drm_device_file;  ///< the EGL device's DRM file; "" for software and surfaceless
};

std::string EglErrorName(EGLint error) {
  switch (error) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default:
      return "EGL error " + std::to_string(error);
  }
}

bool HasExtension(const char* list, const std::string& name) {
  if (list == nullptr) return false;
  const std::string all = std::string(" ") + list + " ";
  return all.find(" " + name + " ") != std::string::npos;
}

// EGL displays are per process: every context of one device (a daemon makes one per session)
// shares its display, and eglTerminate would end them all. Each context holds a reference;
// the last one out terminates the display.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void AcquireDisplay(EGLDisplay display) {
  std::lock_guard lock(g_display_mutex);
  ++g_display_users[display];
}

void ReleaseDisplay(EGLDisplay display) {
  std::lock_guard lock(g_display_mutex);
  auto it = g_display_users.find(display);
  if (it == g_display_users.end() || --it->second == 0) {
    if (it != g_display_users.end()) g_display_users.erase(it);
    eglTerminate(display);
  }
}

// Initializes `display` and creates a current GL 4.5 core context on it (surfaceless: the
// renderers draw into their own framebuffer objects). On failure says why in `why`.
bool MakeContext(EGLDisplay display, EglState* impl, std::string* why) {
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY) {
    *why = "no display (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  if (!eglInitialize(display, &major, &minor)) {
    *why = "eglInitialize failed (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  AcquireDisplay(display);
  if (!HasExtension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context")) {
    *why = "no EGL_KHR_surfaceless_context";
    ReleaseDisplay(display);
    return false;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *why = "eglBindAPI(EGL_OPENGL_API) failed (" + EglErrorName(eglGetError()) + ")";
    ReleaseDisplay(display);
    return false;
  }
  const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint num_configs = 0;
  // Surfaceless contexts need no particular config; take any GL-capable one, or none at all.
  if (!eglChooseConfig(display, config_attributes, &config, 1, &num_configs) || num_configs == 0) {
    config = EGL_NO_CONFIG_KHR;
  }
  // Core 4.5 is the highest profile llvmpipe gives (4.6 fails on Mesa 22.3).
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       4,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT) {
    *why = "eglCreateContext(OpenGL 4.5 core) failed (" + EglErrorName(eglGetError()) + ")";
    ReleaseDisplay(display);
    return false;
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    *why = "eglMakeCurrent failed (" + EglErrorName(eglGetError()) + ")";
    eglDestroyContext(display, context);
    ReleaseDisplay(display);
    return false;
  }
  impl->display = display;
  impl->context = context;
  impl->renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  impl->version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return true;
}

// Undoes a successful MakeContext.
void ReleaseContext(EglState* state) {
  eglMakeCurrent(state->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(state->display, state->context);
  ReleaseDisplay(state->display);
  *state = EglState{};
}

// Mesa's software rasterizers, by GL_RENDERER: a device that does not call itself software
// (EGL_MESA_device_software) may still render with one, e.g. a DRM node without a 3D driver.
bool IsSoftwareRenderer(const std::string& renderer) {
  for (const char* name : {"llvmpipe", "softpipe", "swrast"}) {
    if (renderer.find(name) != std::string::npos) return true;
  }
  return false;
}

// The EGL devices, in EGL's order (the index far-daemon --gpu takes); empty when the device
// platform is not offered.
std::vector<EGLDeviceEXT> QueryDevices(const char* client_extensions) {
  if (!internal::OffersEglDevicePlatform(client_extensions)) return {};
  EGLint num_devices = 0;
  eglQueryDevicesEXT(0, nullptr, &num_devices);
  std::vector<EGLDeviceEXT> devices(static_cast<size_t>(std::max(num_devices, 0)));
  eglQueryDevicesEXT(num_devices, devices.data(), &num_devices);
  devices.resize(static_cast<size_t>(std::max(num_devices, 0)));
  return devices;
}

bool IsSoftwareDevice(EGLDeviceEXT device) {
  return HasExtension(eglQueryDeviceStringEXT(device, EGL_EXTENSIONS), "EGL_MESA_device_software");
}

// "EGL device 1 (hardware, /dev/dri/card1)": how a device is named in logs, errors and status.
// The device's DRM file (/dev/dri/cardN) when EGL_EXT_device_drm gives one, else "".
std::string DrmDeviceFile(EGLDeviceEXT device) {
  if (!HasExtension(eglQueryDeviceStringEXT(device, EGL_EXTENSIONS), "EGL_EXT_device_drm"))
    return {};
  const char* file = eglQueryDeviceStringEXT(device, EGL_DRM_DEVICE_FILE_EXT);
  return file == nullptr ? std::string() : std::string(file);
}

std::string DeviceName(EGLDeviceEXT device, int index) {
  std::string name = "EGL device " + std::to_string(index) +
                     (IsSoftwareDevice(device) ? " (EGL_MESA_device_software" : " (hardware");
  if (const std::string file = DrmDeviceFile(device); !file.empty()) name += ", " + file;
  return name + ")";
}

// Makes a context on EGL device `index` and nothing else (far-daemon --gpu N): the user named
// it, so a software device is used too (its name says so in the log and in status).
bool TryOneDevice(const char* client_extensions, int index, EglState* state,
                  std::vector<std::string>* attempts) {
  const std::vector<EGLDeviceEXT> devices = QueryDevices(client_extensions);
  if (index >= static_cast<int>(devices.size())) {
    attempts->push_back("EGL device " + std::to_string(index) + ": there are " +
                        std::to_string(devices.size()) +
                        " EGL devices (far-daemon --list-gpus lists them)");
    return false;
  }
  const std::string name = DeviceName(devices[static_cast<size_t>(index)], index);
  EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT,
                                                devices[static_cast<size_t>(index)], nullptr);
  std::string why;
  if (!MakeContext(display, state, &why)) {
    attempts->push_back(name + ": " + why);
    return false;
  }
  state->platform = name;
  state->drm_device_file = DrmDeviceFile(devices[static_cast<size_t>(index)]);
  return true;
}

// Makes a context on an EGL device: hardware devices first, software ones
// (EGL_MESA_device_software) only after them, so llvmpipe never shadows a GPU, and not at all
// when `hardware_only` (GlPlatform::kDevice means a GPU: software devices are listed as tried,
// never used). True with `state` current; else every attempt is added to `attempts`.
bool TryDevicePlatform(const char* client_extensions, bool hardware_only, EglState* state,
                       std::vector<std::string>* attempts) {
  if (!internal::OffersEglDevicePlatform(client_extensions)) {
    attempts->push_back("EGL device platform: not offered by this EGL");
    return false;
  }
  const std::vector<EGLDeviceEXT> devices = QueryDevices(client_extensions);
  const int num_devices = static_cast<int>(devices.size());
  if (num_devices == 0) attempts->push_back("EGL device platform: no devices");
  for (bool want_software : {false, true}) {
    for (int i = 0; i < num_devices; ++i) {
      const bool software = IsSoftwareDevice(devices[i]);
      if (software != want_software) continue;
      const std::string name = DeviceName(devices[i], i);
      if (software && hardware_only) {
        attempts->push_back(name + ": a software renderer (Mesa's llvmpipe), not a GPU");
        continue;
      }
      EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      std::string why;
      if (!MakeContext(display, state, &why)) {
        attempts->push_back(name + ": " + why);
        continue;
      }
      if (hardware_only && IsSoftwareRenderer(state->renderer)) {
        attempts->push_back(name + ": GL_RENDERER '" + state->renderer +
                            "' is a software renderer, not a GPU");
        ReleaseContext(state);
        continue;
      }
      state->platform = name;
      state->drm_device_file = DrmDeviceFile(devices[i]);
      return true;
    }
  }
  return false;
}

}  // namespace

bool internal::OffersEglDevicePlatform(const char* client_extensions) {
  return HasExtension(client_extensions, "EGL_EXT_platform_device") &&
         (HasExtension(client_extensions, "EGL_EXT_device_enumeration") ||
          HasExtension(client_extensions, "EGL_EXT_device_base"));
}

struct GlContext::Impl : EglState {};

std::vector<GlContext::Device> GlContext::ListDevices() {
  const std::vector<EGLDeviceEXT> devices =
      QueryDevices(eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS));
  std::vector<Device> list;
  for (size_t i = 0; i < devices.size(); ++i) {
    list.push_back(Device{static_cast<int>(i), DeviceName(devices[i], static_cast<int>(i)),
                          DrmDeviceFile(devices[i])});
  }
  return list;
}

Result<std::unique_ptr<GlContext>> GlContext::Create(GlPlatform platform, int device) {
  const auto gl = LockGl();  // another thread's GL work must not run while a display starts
  auto impl = std::make_unique<Impl>();
  std::vector<std::string> attempts;
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (device >= 0) {
    if (TryOneDevice(client_extensions, device, impl.get(), &attempts))
      return std::unique_ptr<GlContext>(new GlContext(std::move(impl)));
    return MakeError(ErrorCode::kUnavailable,
                     "EGL device " + std::to_string(device) +
                         " (far-daemon --gpu) is not usable: " + attempts.front());
  }

  // 1. The EGL device platform: a real GPU with no X server.
  if (platform != GlPlatform::kSurfaceless &&
      TryDevicePlatform(client_extensions, platform == GlPlatform::kDevice, impl.get(),
                        &attempts)) {
    return std::unique_ptr<GlContext>(new GlContext(std::move(impl)));
  }

  // 2. Mesa's surfaceless platform (llvmpipe on machines with no GPU).
  if (platform != GlPlatform::kDevice) {
    if (!HasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
      attempts.push_back("surfaceless platform: not offered by this EGL");
    } else {
      EGLDisplay display =
          eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      std::string why;
      if (MakeContext(display, impl.get(), &why)) {
        impl->platform = "surfaceless";
        return std::unique_ptr<GlContext>(new GlContext(std::move(impl)));
      }
      attempts.push_back("surfaceless platform: " + why);
    }
  }

  std::string message =
      platform == GlPlatform::kDevice
          ? "no GPU found through the EGL device platform (platform 'device' uses hardware EGL "
            "devices only and never falls back to software; 'auto' does); tried:"
          : "no OpenGL 4.5 core context could be made; tried:";
  for (const auto& attempt : attempts) message += "\n  - " + attempt;
  message += platform == GlPlatform::kDevice
                 ? "\n(a GPU needs its vendor's EGL driver, e.g. libEGL_nvidia.so.0 and its glvnd "
                   "vendor file: docs/gpu.md)"
                 : "\n(install libegl-mesa0 and libgl1-mesa-dri for the software renderer)";
  return MakeError(ErrorCode::kUnavailable, message);
}

GlContext::GlContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

GlContext::~GlContext() {
  const auto gl = LockGl();
  eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(impl_->display, impl_->context);
  ReleaseDisplay(impl_->display);
}

const std::string& GlContext::renderer() const { return impl_->renderer; }
const std::string& GlContext::version() const { return impl_->version; }
const std::string& GlContext::platform_description() const { return impl_->platform; }
const std::string& GlContext::drm_device_file() const { return impl_->drm_device_file; }

}  // namespace far
