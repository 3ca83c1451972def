#pragma once

#include "methods/method.h"

namespace canopy {

// Octahedral impostors (Brucks 2018, as engines draw far trees today): one camera-facing quad
// per tree textured from an atlas of N×N orthographic frames on a (hemi-)octahedron, the three
// nearest frames blended and reprojected with their depth.
void registerOctahedral(MethodRegistry& registry);

}  // namespace canopy
