#include "common/gl/api.h"

#include <cassert>
#include <stdexcept>

#include <fmt/format.h>

namespace canopy::gl {
namespace {
const Api* gCurrent = nullptr;
}

Api loadApi(const ProcResolver& resolve) {
  Api table;
#define CANOPY_GL_LOAD(type, name)                                                    \
  table.name = reinterpret_cast<type>(resolve("gl" #name));                           \
  if (table.name == nullptr) {                                                        \
    throw std::runtime_error("OpenGL entry point gl" #name " could not be resolved"); \
  }
  CANOPY_GL_FUNCTIONS(CANOPY_GL_LOAD)
#undef CANOPY_GL_LOAD
  return table;
}

const Api& api() {
  assert(gCurrent != nullptr && "no OpenGL context is current");
  return *gCurrent;
}

void setCurrentApi(const Api* table) {
  gCurrent = table;
}

void checkError(const char* where) {
  const GLenum error = api().GetError();
  if (error != GL_NO_ERROR) {
    throw std::runtime_error(fmt::format("OpenGL error 0x{:04x} at {}", error, where));
  }
}

}  // namespace canopy::gl
