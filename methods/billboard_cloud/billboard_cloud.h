#pragma once

#include "methods/method.h"

namespace canopy {

// The classic textured billboard cloud (Décoret et al. 2003; Behrendt et al. 2005): one RGBA
// texture per billboard, the orthographic image of its leaves, in one mipmapped atlas.
void registerBillboardCloud(MethodRegistry& registry);

}  // namespace canopy
