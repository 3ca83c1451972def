#pragma once

#include "methods/method.h"

namespace canopy {

// Multi-layered indirect texturing (García, Patow, Szirmay-Kalos, Sbert 2007).
void registerMultilayerIndirect(MethodRegistry& registry);

}  // namespace canopy
