// EGL backend without a window: an EGL device (a GPU with no display, e.g. NVIDIA in a cluster)
// when one is present, otherwise Mesa's surfaceless platform (llvmpipe on this machine).
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/gl/backends.h"

namespace canopy::gl {
namespace {

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t length = std::strlen(name);
  for (const char* p = std::strstr(list, name); p; p = std::strstr(p + 1, name)) {
    const bool startOk = p == list || p[-1] == ' ';
    const bool endOk = p[length] == ' ' || p[length] == '\0';
    if (startOk && endOk) return true;
  }
  return false;
}

class EglContext final : public Context {
 public:
  EglContext() : Context(Backend::kEgl) {
    for (EGLDisplay display : candidateDisplays()) {
      if (tryCreate(display)) break;
    }
    if (mContext == EGL_NO_CONTEXT) {
      throwInputError(
          "OpenGL backend egl: no EGL device or surfaceless display gives a 4.3+ "
          "core context (EGL error 0x{:x})",
          eglGetError());
    }
    bind();
    resolveEntryPoints(
        [](const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); });
  }

  ~EglContext() override {
    eglMakeCurrent(mDisplay, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (mSurface != EGL_NO_SURFACE) eglDestroySurface(mDisplay, mSurface);
    eglDestroyContext(mDisplay, mContext);
    // The display is shared by every context on it, so it is not terminated here.
  }

 protected:
  void bind() override {
    if (!eglMakeCurrent(mDisplay, mSurface, mSurface, mContext)) {
      throwInputError("OpenGL backend egl: eglMakeCurrent failed (0x{:x})", eglGetError());
    }
  }

 private:
  // Hardware devices first, then Mesa surfaceless, then software devices.
  static std::vector<EGLDisplay> candidateDisplays() {
    std::vector<EGLDisplay> hardware, software;
    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!getPlatformDisplay) return {eglGetDisplay(EGL_DEFAULT_DISPLAY)};
    auto queryDevices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto queryDeviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    if (queryDevices && hasExtension(clientExtensions, "EGL_EXT_platform_device")) {
      EGLDeviceEXT devices[16];
      EGLint count = 0;
      if (queryDevices(16, devices, &count)) {
        for (EGLint i = 0; i < count; ++i) {
          const char* extensions =
              queryDeviceString ? queryDeviceString(devices[i], EGL_EXTENSIONS) : nullptr;
          EGLDisplay display = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
          if (display == EGL_NO_DISPLAY) continue;
          (hasExtension(extensions, "EGL_MESA_device_software") ? software : hardware)
              .push_back(display);
        }
      }
    }
    std::vector<EGLDisplay> ordered = hardware;
    if (hasExtension(clientExtensions, "EGL_MESA_platform_surfaceless")) {
      EGLDisplay display =
          getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (display != EGL_NO_DISPLAY) ordered.push_back(display);
    }
    ordered.insert(ordered.end(), software.begin(), software.end());
    return ordered;
  }

  bool tryCreate(EGLDisplay display) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) return false;
    if (!eglBindAPI(EGL_OPENGL_API)) return false;
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    const bool surfaceless = hasExtension(extensions, "EGL_KHR_surfaceless_context");
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!surfaceless || !hasExtension(extensions, "EGL_KHR_no_config_context")) {
      const EGLint configAttributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                         EGL_OPENGL_BIT, EGL_NONE};
      EGLint count = 0;
      if (!eglChooseConfig(display, configAttributes, &config, 1, &count) || count == 0)
        return false;
    }
    for (const EGLint minorVersion : {5, 3}) {
      const EGLint contextAttributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                          4,
                                          EGL_CONTEXT_MINOR_VERSION,
                                          minorVersion,
                                          EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                          EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                          EGL_NONE};
      mContext = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttributes);
      if (mContext != EGL_NO_CONTEXT) break;
    }
    if (mContext == EGL_NO_CONTEXT) return false;
    mDisplay = display;
    if (!surfaceless) {
      const EGLint surfaceAttributes[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
      mSurface = eglCreatePbufferSurface(display, config, surfaceAttributes);
      if (mSurface == EGL_NO_SURFACE) {
        eglDestroyContext(display, mContext);
        mContext = EGL_NO_CONTEXT;
        return false;
      }
    }
    return true;
  }

  EGLDisplay mDisplay = EGL_NO_DISPLAY;
  EGLContext mContext = EGL_NO_CONTEXT;
  EGLSurface mSurface = EGL_NO_SURFACE;
};

}  // namespace

std::unique_ptr<Context> createEglContext(const ContextOptions&) {
  return std::make_unique<EglContext>();
}

}  // namespace canopy::gl
