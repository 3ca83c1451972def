#pragma once

#include "methods/method.h"

namespace canopy {

// The reference: the wood mesh and every leaf as a textured quad with alpha test.
void registerPolygonal(MethodRegistry& registry);

}  // namespace canopy
