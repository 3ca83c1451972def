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
// reference at most one leaf image. Leaves lose their exact positions (each sits at the centre
// of a cell) and their exact orientations (quantized images): the regular look the multi-layer
// paper sets out to fix. Every leaf is shown: front to back, each leaf takes the free cell
// nearest its projected centre within `kSearchRadius` cells, and where a billboard's leaves
// crowd so that one finds none, that billboard's cells halve until all fit.
struct SingleLeafGrid {
  glm::ivec2 cells{1, 1};       // columns (along axisU), rows (along axisV)
  float cellLength = 1.0f;      // side of a cell on the billboard plane (after any halving)
  std::vector<int32_t> leaf;    // per cell, row-major: the leaf index, or -1 when empty
  std::vector<uint32_t> image;  // per cell: oriented image index (meaningful where leaf >= 0)
  std::vector<float> scale;     // per cell: the leaf's length in cell lengths (its image's size)
  std::vector<float> height;    // per cell: the leaf centre's height along the billboard normal
  size_t leavesPlaced = 0;
};

inline constexpr int kSearchRadius = 2;  // cells a leaf may move from its own

// Cells are squares of side `cellLength` (rounded so a whole number spans the billboard), halved
// per billboard until every leaf has one, at most `maxCells` per side; past that, a leaf takes
// the nearest free cell at any distance, and only a billboard with fewer cells than leaves
// leaves some out (leavesPlaced says how many were placed).
std::vector<SingleLeafGrid> buildSingleLeafGrids(const Tree& tree, const BillboardCloud& cloud,
                                                 float cellLength, const OrientationBins& bins,
                                                 int maxCells);

// Mean of 2·max(half extents) over the leaves.
float meanLeafLength(const Tree& tree);

}  // namespace canopy
