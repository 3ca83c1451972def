#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

namespace canopy {

// Billboard draw orders sorted front to back for a few view directions. Alpha-tested impostor
// shaders discard, yet the depth test still runs before them (llvmpipe, and GPUs with early
// depth): drawn nearest first, billboards hide the fragments behind them before their shaders
// run. Each instance is drawn with the order of the direction nearest to its own view of the tree.
struct ViewOrders {
  struct Range {
    uint32_t first = 0;  // billboards
    uint32_t count = 0;
  };
  std::vector<glm::vec3> directions;  // unit, tree-local, from the tree towards the viewer
  std::vector<Range> ranges;          // the sorted levels, contiguous from billboard 0
  uint32_t perDirection = 0;          // billboards in the sorted levels
  // Per direction, perDirection billboard indices: each range sorted on its own (range by range,
  // so a range's slots are first + its position), front first.
  std::vector<uint32_t> order;

  bool empty() const { return directions.empty(); }
  // The direction nearest `towardsViewer` (tree-local, from the tree's centre; any length).
  int nearest(const glm::vec3& towardsViewer) const;
  // The slot (into `order`) where `range`'s billboards start for `direction`.
  uint32_t firstSlot(int direction, size_t range) const {
    return uint32_t(direction) * perDirection + ranges[range].first;
  }
};

// `count` directions spread evenly over the sphere (a Fibonacci lattice; deterministic).
std::vector<glm::vec3> sphereDirections(int count);

// Sorts every range of `centers` (tree-local billboard centres) by the distance along each of
// `directions` sphere directions, nearest the viewer first (ties by index). `ranges` must be
// contiguous from billboard 0. An orthographic order: for a perspective camera outside the tree
// it is nearly front to back, which is all the depth test needs to save work.
ViewOrders buildViewOrders(std::span<const glm::vec3> centers,
                           const std::vector<ViewOrders::Range>& ranges, int directions);

}  // namespace canopy
