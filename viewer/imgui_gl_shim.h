#pragma once
// Force-included into Debian's imgui_impl_opengl3.cpp (built with IMGUI_IMPL_OPENGL_LOADER_CUSTOM)
// so Dear ImGui calls OpenGL through Canopy's table, resolved by the current backend, like every
// other GL call here — never through a second loader or libGL's exported symbols (DESIGN.md).
// Each glXxx is a function object with the entry point's exact parameter types (so NULL and
// integer literals convert as they would for a real prototype).
#include "common/gl/api.h"

namespace canopy::gl::imgui_shim {
template <typename F>
struct Entry;
template <typename R, typename... A>
struct Entry<R (*)(A...)> {
  template <auto Member>
  struct Call {
    R operator()(A... args) const { return (::canopy::gl::api().*Member)(args...); }
  };
};
}  // namespace canopy::gl::imgui_shim

#define CANOPY_IMGUI_GL_WRAPPER(type, name)                                                       \
  inline constexpr ::canopy::gl::imgui_shim::Entry<type>::template Call<&::canopy::gl::Api::name> \
      gl##name{};
CANOPY_GL_FUNCTIONS(CANOPY_IMGUI_GL_WRAPPER)
#undef CANOPY_IMGUI_GL_WRAPPER
