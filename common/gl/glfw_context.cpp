// GLFW backend: a window with an OpenGL core context (the viewer), hidden unless asked.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <string>

#include "common/error.h"
#include "common/gl/backends.h"

namespace canopy::gl {
namespace {

std::string gLastGlfwError;

void recordGlfwError(int code, const char* description) {
  gLastGlfwError = std::to_string(code) + ": " + (description ? description : "");
}

int gLiveWindows = 0;

class GlfwContext final : public Context {
 public:
  explicit GlfwContext(const ContextOptions& options) : Context(Backend::kGlfw) {
    glfwSetErrorCallback(recordGlfwError);
    if (gLiveWindows == 0 && !glfwInit()) {
      throwInputError(
          "OpenGL backend glfw: no display ({}); set DISPLAY, run under xvfb-run, or "
          "use --gl osmesa",
          gLastGlfwError);
    }
    ++gLiveWindows;
    for (const int minor : {5, 3}) {
      glfwDefaultWindowHints();
      glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
      glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
      glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
      glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
      glfwWindowHint(GLFW_VISIBLE, options.visibleWindow ? GLFW_TRUE : GLFW_FALSE);
      mWindow = glfwCreateWindow(options.windowWidth, options.windowHeight, options.title.c_str(),
                                 nullptr, nullptr);
      if (mWindow) break;
    }
    if (!mWindow) {
      releaseGlfw();
      throwInputError("OpenGL backend glfw: cannot open a window with a 4.3+ core context ({})",
                      gLastGlfwError);
    }
    bind();
    resolveEntryPoints(
        [](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); });
  }

  ~GlfwContext() override {
    glfwDestroyWindow(mWindow);
    releaseGlfw();
  }

  void swapBuffers() override { glfwSwapBuffers(mWindow); }
  void* nativeWindow() override { return mWindow; }

 protected:
  void bind() override { glfwMakeContextCurrent(mWindow); }

 private:
  static void releaseGlfw() {
    if (--gLiveWindows == 0) glfwTerminate();
  }

  GLFWwindow* mWindow = nullptr;
};

}  // namespace

std::unique_ptr<Context> createGlfwContext(const ContextOptions& options) {
  return std::make_unique<GlfwContext>(options);
}

}  // namespace canopy::gl
