#pragma once

#include "methods/method.h"

namespace canopy {

// Bounding-box hierarchy of images (Lluch, Camahort, Vivó 2004).
void registerBboxHierarchy(MethodRegistry& registry);

}  // namespace canopy
