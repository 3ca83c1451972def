#include "methods/bbox_hierarchy/box_hierarchy.h"

#include <algorithm>
#include <numeric>

#include <glm/geometric.hpp>

namespace canopy {

BoxHierarchy hierarchyFromBranches(const Tree& tree) {
  BoxHierarchy hierarchy;
  hierarchy.source = "branches";
  hierarchy.leafOrder.resize(tree.leaves.size());
  std::iota(hierarchy.leafOrder.begin(), hierarchy.leafOrder.end(),
            0u);  // leaves are sorted by node
  for (const BranchNode& branch : tree.branches) {
    BoxNode node;
    node.parent = branch.parent;
    node.children = branch.children;
    node.level = branch.level;
    node.box = branch.bounds;
    node.leafBegin = branch.leafBegin;
    node.leafEnd = branch.leafEnd;
    node.subtreeLeafEnd = branch.subtreeLeafEnd;
    hierarchy.nodes.push_back(std::move(node));
  }
  return hierarchy;
}

namespace {

void splitSpatially(const Tree& tree, BoxHierarchy& hierarchy, std::vector<uint32_t>& leaves,
                    size_t begin, size_t end, int32_t parent, int32_t level, int maxLeaves) {
  const auto index = static_cast<int32_t>(hierarchy.nodes.size());
  hierarchy.nodes.emplace_back();
  hierarchy.nodes[index].parent = parent;
  hierarchy.nodes[index].level = level;
  if (parent >= 0) hierarchy.nodes[parent].children.push_back(index);
  Aabb box;
  for (size_t i = begin; i < end; ++i) {
    for (int c = 0; c < 4; ++c) box.extend(tree.leaves[leaves[i]].corner(c));
  }
  hierarchy.nodes[index].box = box;
  if (end - begin <= size_t(maxLeaves)) {
    hierarchy.nodes[index].leafBegin = static_cast<uint32_t>(begin);
    hierarchy.nodes[index].leafEnd = static_cast<uint32_t>(end);
    hierarchy.nodes[index].subtreeLeafEnd = static_cast<uint32_t>(end);
    return;
  }
  const glm::vec3 extent = box.extent();
  const int axis =
      extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const size_t middle = (begin + end) / 2;
  std::nth_element(leaves.begin() + begin, leaves.begin() + middle, leaves.begin() + end,
                   [&](uint32_t a, uint32_t b) {
                     const float ca = tree.leaves[a].center[axis], cb = tree.leaves[b].center[axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  hierarchy.nodes[index].leafBegin = hierarchy.nodes[index].leafEnd = static_cast<uint32_t>(begin);
  splitSpatially(tree, hierarchy, leaves, begin, middle, index, level + 1, maxLeaves);
  splitSpatially(tree, hierarchy, leaves, middle, end, index, level + 1, maxLeaves);
  hierarchy.nodes[index].subtreeLeafEnd = static_cast<uint32_t>(end);
}

}  // namespace

BoxHierarchy spatialHierarchy(const Tree& tree, int maxLeaves) {
  BoxHierarchy hierarchy;
  hierarchy.source = "spatial";
  hierarchy.leafOrder.resize(tree.leaves.size());
  std::iota(hierarchy.leafOrder.begin(), hierarchy.leafOrder.end(), 0u);
  splitSpatially(tree, hierarchy, hierarchy.leafOrder, 0, tree.leaves.size(), -1, 0,
                 std::max(1, maxLeaves));
  return hierarchy;
}

void pruneByVolumeRatio(BoxHierarchy& hierarchy, float threshold) {
  for (size_t n = 0; n < hierarchy.nodes.size(); ++n) {
    BoxNode& node = hierarchy.nodes[n];
    const bool hasLeaves = node.subtreeLeafEnd > node.leafBegin;
    if (node.parent < 0) {
      node.textured = hasLeaves;
      continue;
    }
    const float parentVolume = hierarchy.nodes[node.parent].box.volume();
    const float ratio = parentVolume > 0.0f ? node.box.volume() / parentVolume : 0.0f;
    node.textured = hasLeaves && ratio >= threshold;
  }
}

void walkHierarchy(const BoxHierarchy& hierarchy, const std::vector<float>& lodDistance,
                   const glm::vec3& viewer, HierarchyWalk& walk) {
  walk.boxes.clear();
  walk.leafNodes.clear();
  if (hierarchy.nodes.empty()) return;
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const int32_t n = stack.back();
    stack.pop_back();
    const BoxNode& node = hierarchy.nodes[n];
    if (node.subtreeLeafEnd == node.leafBegin) continue;  // nothing to draw below
    if (node.textured && glm::length(viewer - node.box.center()) > lodDistance[n]) {
      walk.boxes.push_back(n);
      continue;
    }
    if (node.leafEnd > node.leafBegin) walk.leafNodes.push_back(n);
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.push_back(*it);
  }
}

}  // namespace canopy
