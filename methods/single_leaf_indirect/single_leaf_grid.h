#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "common/tree.h"
#include "methods/common/billboard_cloud.h"
#include "methods/common/leaf_orientations.h"

namespace canopy {

// The indirect texture of single-leaf indirect texturing (García, Sbert, Szirmay-Kalos 2005, as
// the 2007 paper's §2 and Fig. 2 describe it): a regular grid over a billboard whose cells each
// reference at most one leaf image. A leaf lands in the cell that contains its projected centre;
// where several do, the one nearest the billboard's front wins. Leaves lose their positions
// within the cell, their overlaps and the leaves that lost — the regular, sparser look the
// multi-layer paper sets out to fix.
struct SingleLeafGrid {
  glm::ivec2 cells{1, 1};       // columns (along axisU), rows (along axisV)
  std::vector<int32_t> leaf;    // per cell, row-major: the leaf index, or -1 when empty
  std::vector<uint32_t> image;  // per cell: oriented image index (meaningful where leaf >= 0)
};

// Cells are squares of side `cellLength` (rounded so a whole number spans the billboard), at
// most `maxCells` per side.
std::vector<SingleLeafGrid> buildSingleLeafGrids(const Tree& tree, const BillboardCloud& cloud,
                                                 float cellLength, const OrientationBins& bins,
                                                 int maxCells);

// Mean of 2·max(half extents) over the leaves.
float meanLeafLength(const Tree& tree);

}  // namespace canopy
