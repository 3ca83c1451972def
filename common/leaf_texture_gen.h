#pragma once

#include <cstdint>

#include "common/tree.h"

namespace canopy {

// Draws a leaf procedurally: an outline with a pointed tip and a petiole, a midrib, paired veins,
// mottled colour, a lighter and greyer underside and a normal map of the venation.
// The base of the blade is at v = 0 (image row 0), the tip near v = 1. Deterministic in `variant`.
LeafTexture drawLeafTexture(int size, uint32_t variant);

}  // namespace canopy
