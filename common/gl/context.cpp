#include "common/gl/context.h"

#include "common/error.h"
#include "common/gl/api.h"
#include "common/gl/backends.h"

namespace canopy::gl {

Context::Context(Backend backend) : mBackend(backend), mApi(std::make_unique<Api>()) {}

Context::~Context() {
  setCurrentApi(nullptr);
}

void Context::makeCurrent() {
  bind();
  setCurrentApi(mApi.get());
}

void Context::resolveEntryPoints(const std::function<void*(const char*)>& resolve) {
  *mApi = loadApi(resolve);
  setCurrentApi(mApi.get());
}

std::string Context::renderer() const {
  const auto* text = reinterpret_cast<const char*>(mApi->GetString(GL_RENDERER));
  return text ? text : "";
}

std::string Context::version() const {
  const auto* text = reinterpret_cast<const char*>(mApi->GetString(GL_VERSION));
  return text ? text : "";
}

std::string Context::vendor() const {
  const auto* text = reinterpret_cast<const char*>(mApi->GetString(GL_VENDOR));
  return text ? text : "";
}

std::unique_ptr<Context> createContext(const ContextOptions& options) {
  std::unique_ptr<Context> context;
  switch (options.backend) {
    case Backend::kOsMesa:
      context = createOsMesaContext(options);
      break;
    case Backend::kEgl:
      context = createEglContext(options);
      break;
    case Backend::kGlfw:
      context = createGlfwContext(options);
      break;
  }
  // A context whose strings are null renders nothing (the libGL/libOSMesa trap): refuse it.
  if (context->renderer().empty()) {
    throwInputError("OpenGL backend {}: context reports no GL_RENDERER; draws would be no-ops",
                    backendName(options.backend));
  }
  return context;
}

Backend parseBackend(std::string_view name) {
  if (name == "osmesa") return Backend::kOsMesa;
  if (name == "egl") return Backend::kEgl;
  if (name == "glfw") return Backend::kGlfw;
  throwInputError("--gl: unknown OpenGL backend '{}' (expected osmesa, egl or glfw)", name);
}

std::string_view backendName(Backend backend) {
  switch (backend) {
    case Backend::kOsMesa:
      return "osmesa";
    case Backend::kEgl:
      return "egl";
    case Backend::kGlfw:
      return "glfw";
  }
  return "?";
}

}  // namespace canopy::gl
