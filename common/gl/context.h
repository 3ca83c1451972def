#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace canopy::gl {

struct Api;

// The three ways Canopy reaches OpenGL. Code above createContext never branches on them.
enum class Backend {
  kOsMesa,  // headless, Mesa llvmpipe in-process: the default on machines without a GPU
  kEgl,     // headless, a GPU device (e.g. NVIDIA without display) or Mesa surfaceless
  kGlfw,    // a window (the viewer; also usable headless under Xvfb)
};

struct ContextOptions {
  Backend backend = Backend::kOsMesa;
  int windowWidth = 1280;      // GLFW only: the window's size
  int windowHeight = 1024;     // GLFW only
  bool visibleWindow = false;  // GLFW only: show the window (the viewer) or keep it hidden
  std::string title = "Canopy";
};

// An OpenGL 4.3+ core context and the entry-point table resolved through its own backend.
class Context {
 public:
  virtual ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  Backend backend() const { return mBackend; }
  // Makes this context current on the calling thread and its table the one gl::api() returns.
  void makeCurrent();
  const Api& api() const { return *mApi; }
  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION
  std::string vendor() const;    // GL_VENDOR
  virtual void swapBuffers() {}
  virtual void* nativeWindow() { return nullptr; }  // GLFWwindow* for the GLFW backend

 protected:
  explicit Context(Backend backend);
  virtual void bind() = 0;
  // Called by each backend once its context is current.
  void resolveEntryPoints(const std::function<void*(const char*)>& resolve);

 private:
  Backend mBackend;
  std::unique_ptr<Api> mApi;
};

// The one factory. Throws InputError with a clear line when the backend cannot be created
// (no display for GLFW, no EGL device, ...), so each main can exit with code 2.
std::unique_ptr<Context> createContext(const ContextOptions& options);

// "osmesa" | "egl" | "glfw"; InputError naming the value otherwise.
Backend parseBackend(std::string_view name);
std::string_view backendName(Backend backend);

}  // namespace canopy::gl
