#pragma once

#include "methods/method.h"

namespace canopy {

// Single-leaf indirect texturing (García, Sbert, Szirmay-Kalos 2005; 2007 paper §2, Fig. 2).
void registerSingleLeafIndirect(MethodRegistry& registry);

}  // namespace canopy
