#include "methods/single_leaf_indirect/single_leaf_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace canopy {

float meanLeafLength(const Tree& tree) {
  double sum = 0.0;
  for (const Leaf& leaf : tree.leaves)
    sum += 2.0 * std::max(leaf.halfExtents.x, leaf.halfExtents.y);
  return tree.leaves.empty() ? 1.0f : float(sum / double(tree.leaves.size()));
}

std::vector<SingleLeafGrid> buildSingleLeafGrids(const Tree& tree, const BillboardCloud& cloud,
                                                 float cellLength, const OrientationBins& bins,
                                                 int maxCells) {
  std::vector<SingleLeafGrid> grids;
  grids.reserve(cloud.billboards.size());
  for (const Billboard& billboard : cloud.billboards) {
    SingleLeafGrid grid;
    const auto cellsAlong = [&](float halfExtent) {
      return std::clamp(static_cast<int>(std::lround(2.0f * halfExtent / cellLength)), 1, maxCells);
    };
    grid.cells = {cellsAlong(billboard.halfExtents.x), cellsAlong(billboard.halfExtents.y)};
    grid.leaf.assign(size_t(grid.cells.x) * grid.cells.y, -1);
    grid.image.assign(grid.leaf.size(), 0);
    std::vector<float> front(grid.leaf.size(), std::numeric_limits<float>::lowest());
    for (uint32_t index : billboard.leaves) {
      const Leaf& leaf = tree.leaves[index];
      const glm::vec2 p = billboard.toPlane(leaf.center);
      const int cx =
          std::clamp(static_cast<int>(std::floor((p.x + billboard.halfExtents.x) /
                                                 (2.0f * billboard.halfExtents.x) * grid.cells.x)),
                     0, grid.cells.x - 1);
      const int cy =
          std::clamp(static_cast<int>(std::floor((p.y + billboard.halfExtents.y) /
                                                 (2.0f * billboard.halfExtents.y) * grid.cells.y)),
                     0, grid.cells.y - 1);
      const size_t cell = size_t(cy) * grid.cells.x + cx;
      const float height = glm::dot(leaf.center - billboard.center, billboard.normal);
      if (height > front[cell]) {
        front[cell] = height;
        grid.leaf[cell] = static_cast<int32_t>(index);
        grid.image[cell] = orientedImageIndex(leaf, billboard, bins);
      }
    }
    grids.push_back(std::move(grid));
  }
  return grids;
}

}  // namespace canopy
