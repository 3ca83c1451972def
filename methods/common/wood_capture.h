#pragma once

#include <cstdint>
#include <vector>

#include "common/tree.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// Which wood triangles a cloud's images can hold, and in which billboard. The candidates for a
// triangle are the billboards whose rectangle contains its three corners' projections with every
// corner within `maxDistance` of the plane (its flattening error, world units); it goes to the
// candidate its facet faces most squarely (so, as for leaves, the facet keeps its projected area
// from every view), the nearest among equals. One list of triangle indices per billboard; a
// triangle in none stays geometry.
std::vector<std::vector<uint32_t>> assignWoodToBillboards(const WoodMesh& wood,
                                                          const std::vector<Billboard>& billboards,
                                                          float maxDistance);

}  // namespace canopy
