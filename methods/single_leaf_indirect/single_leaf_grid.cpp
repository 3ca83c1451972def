#include "methods/single_leaf_indirect/single_leaf_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/geometric.hpp>

namespace canopy {

float meanLeafLength(const Tree& tree) {
  double sum = 0.0;
  for (const Leaf& leaf : tree.leaves)
    sum += 2.0 * std::max(leaf.halfExtents.x, leaf.halfExtents.y);
  return tree.leaves.empty() ? 1.0f : float(sum / double(tree.leaves.size()));
}

namespace {

// Places `order`'s leaves (front to back) on a grid of `cells`, each in the free cell nearest
// its projected centre within `radius` cells (any distance when radius < 0). False when a leaf
// finds no free cell within the radius.
bool placeLeaves(const Tree& tree, const Billboard& billboard, const std::vector<uint32_t>& order,
                 int radius, SingleLeafGrid& grid) {
  const glm::vec2 cellSize = 2.0f * billboard.halfExtents / glm::vec2(grid.cells);
  grid.leaf.assign(size_t(grid.cells.x) * grid.cells.y, -1);
  grid.leavesPlaced = 0;
  const int reach = radius >= 0 ? radius : std::max(grid.cells.x, grid.cells.y);
  for (uint32_t index : order) {
    const glm::vec2 p = (billboard.toPlane(tree.leaves[index].center) + billboard.halfExtents) /
                        cellSize;  // in cells
    const glm::ivec2 home = glm::clamp(glm::ivec2(glm::floor(p)), glm::ivec2(0), grid.cells - 1);
    int best = -1;
    for (int ring = 0; ring <= reach && best < 0; ++ring) {
      float bestDistance = std::numeric_limits<float>::max();
      for (int y = home.y - ring; y <= home.y + ring; ++y) {
        for (int x = home.x - ring; x <= home.x + ring; ++x) {
          if (std::max(std::abs(x - home.x), std::abs(y - home.y)) != ring) continue;
          if (x < 0 || y < 0 || x >= grid.cells.x || y >= grid.cells.y) continue;
          const int cell = y * grid.cells.x + x;
          if (grid.leaf[size_t(cell)] >= 0) continue;
          const float distance = glm::length(glm::vec2(x + 0.5f, y + 0.5f) - p);
          if (distance < bestDistance) bestDistance = distance, best = cell;
        }
      }
    }
    if (best < 0) {
      if (radius >= 0) return false;
      continue;  // no free cell anywhere: the leaf is left out
    }
    grid.leaf[size_t(best)] = static_cast<int32_t>(index);
    ++grid.leavesPlaced;
  }
  return true;
}

}  // namespace

std::vector<SingleLeafGrid> buildSingleLeafGrids(const Tree& tree, const BillboardCloud& cloud,
                                                 float cellLength, const OrientationBins& bins,
                                                 int maxCells) {
  std::vector<SingleLeafGrid> grids;
  grids.reserve(cloud.billboards.size());
  for (const Billboard& billboard : cloud.billboards) {
    const auto heightOf = [&](uint32_t index) {
      return glm::dot(tree.leaves[index].center - billboard.center, billboard.normal);
    };
    std::vector<uint32_t> order = billboard.leaves;
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return heightOf(a) > heightOf(b) || (heightOf(a) == heightOf(b) && a < b);
    });
    SingleLeafGrid grid;
    for (float length = cellLength;; length *= 0.5f) {
      const auto cellsAlong = [&](float halfExtent) {
        return std::clamp(static_cast<int>(std::lround(2.0f * halfExtent / length)), 1, maxCells);
      };
      grid.cells = {cellsAlong(billboard.halfExtents.x), cellsAlong(billboard.halfExtents.y)};
      const bool finest = grid.cells.x == maxCells || grid.cells.y == maxCells;
      if (placeLeaves(tree, billboard, order, finest ? -1 : kSearchRadius, grid)) break;
    }
    // Non-square rounding: the cell length is the mean of the two sides.
    const glm::vec2 cellSize = 2.0f * billboard.halfExtents / glm::vec2(grid.cells);
    grid.cellLength = 0.5f * (cellSize.x + cellSize.y);
    grid.image.assign(grid.leaf.size(), 0);
    grid.scale.assign(grid.leaf.size(), 0.0f);
    grid.height.assign(grid.leaf.size(), 0.0f);
    for (size_t cell = 0; cell < grid.leaf.size(); ++cell) {
      if (grid.leaf[cell] < 0) continue;
      const Leaf& leaf = tree.leaves[size_t(grid.leaf[cell])];
      grid.image[cell] = orientedImageIndex(leaf, billboard, bins);
      grid.scale[cell] = 2.0f * std::max(leaf.halfExtents.x, leaf.halfExtents.y) / grid.cellLength;
      grid.height[cell] = heightOf(uint32_t(grid.leaf[cell]));
    }
    grids.push_back(std::move(grid));
  }
  return grids;
}

}  // namespace canopy
