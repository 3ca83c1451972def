#pragma once

#include "methods/method.h"

namespace canopy {

// The reference: the wood mesh and every leaf as a textured quad with alpha test.
void registerPolygonal(MethodRegistry& registry);

// The reference at its default parameters, for methods that turn into the mesh near the camera.
std::unique_ptr<Method> makePolygonalReference();

}  // namespace canopy
