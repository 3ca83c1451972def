#pragma once

// Backend constructors, visible to the factory in context.cpp only.
#include <memory>

#include "common/gl/context.h"

namespace canopy::gl {

std::unique_ptr<Context> createOsMesaContext(const ContextOptions& options);
std::unique_ptr<Context> createEglContext(const ContextOptions& options);
std::unique_ptr<Context> createGlfwContext(const ContextOptions& options);

}  // namespace canopy::gl
