#pragma once

#include "methods/method.h"

namespace canopy {

// Volumetric opacity reconstruction with view-dependent billboards (Reche-Martinez, Martin,
// Drettakis 2004).
void registerVolumetricOpacity(MethodRegistry& registry);

}  // namespace canopy
