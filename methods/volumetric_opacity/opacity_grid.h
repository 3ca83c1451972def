#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "common/captures.h"
#include "common/tree.h"

namespace canopy {

// The recursive grid of §7: a cube split 3×3×3 per level; a cell outside the visual hull of the
// alpha masks is not subdivided, so only non-empty cells reach the finest level, where each holds
// a transparency t = 1 − α (§5). Finest cells are addressed on the dense side³ lattice.
struct OpacityGrid {
  Aabb root;      // a cube
  int level = 0;  // subdivisions; side = 3^level cells per axis
  int side = 1;
  float cellSize = 0.0f;              // world size of a finest cell
  std::vector<glm::ivec3> cells;      // lattice coordinates of the non-empty finest cells
  std::vector<float> transparency;    // per cell, in (0, 1]
  std::vector<int32_t> lattice;       // side³: cell index, or -1 for empty space
  std::vector<int> nonEmptyPerLevel;  // cells kept at each level 0..level (the report's)

  glm::vec3 cellCenter(size_t cell) const {
    return root.min + (glm::vec3(cells[cell]) + 0.5f) * cellSize;
  }
  Aabb cellBox(size_t cell) const;
  // Sets the root cube and the level, and from them side = 3^level and the cell size.
  void setLattice(const Aabb& cube, int subdivisions);
  int32_t cellAt(glm::ivec3 c) const {
    return lattice[(size_t(c.z) * side + size_t(c.y)) * side + size_t(c.x)];
  }
  // Drops cells whose transparency is >= `threshold` (they become empty space).
  void removeTransparentCells(float threshold);
  void rebuildLattice();
};

// One input view with what every later step asks of it.
struct OpacityView {
  PixelCamera camera;
  const ImageRgbaF* image;  // linear premultiplied, alpha = pixel opacity α_p
  AlphaIntegral alpha;
};
std::vector<OpacityView> prepareViews(const std::vector<CapturedView>& views,
                                      float foregroundAlpha);

// The smallest cube around `bounds` (slightly enlarged so surface cells are not cut).
Aabb enclosingCube(const Aabb& bounds);

// Builds the grid (§7) by recursive subdivision of the cells no view carves away
// (viewCarvesBox: outside the visual hull of the alpha masks), and initialises each cell (§5)
// with 1 − min over views of the mean alpha in its projection.
OpacityGrid buildOpacityGrid(const Aabb& cube, int level, const std::vector<OpacityView>& views,
                             float foregroundAlpha);

// A cell crossed by a ray with the Appendix A weight w = V / V_c: the volume of the pixel's
// pyramid inside the cell over the cell's volume.
struct RaySegment {
  int32_t cell;
  float weight;
  float length;  // of the ray inside the cell, in cell sizes
};

// The grid one level coarser (§7's recursive grid, read upwards): a parent holds its 27
// children, and its optical depth −log t is the children's sum over the nine columns of three a
// ray crosses on average (Σ −log t_child / 9), so a ray through a uniformly filled parent sees
// the opacity the children gave it. Used for the levels of detail.
OpacityGrid coarsenGrid(const OpacityGrid& fine, float minTransparency);

// The non-empty cells the ray through pixel (px, py) (pixel centre at +0.5) crosses, front to
// back, by a 3D-DDA walk of the lattice. Returns false when the ray misses the grid.
bool traceRay(const OpacityGrid& grid, const PixelCamera& camera, float px, float py,
              std::vector<RaySegment>& out);

}  // namespace canopy
