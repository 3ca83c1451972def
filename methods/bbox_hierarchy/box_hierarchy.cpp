#include "methods/bbox_hierarchy/box_hierarchy.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <tuple>

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

// Nearest-point queries over a set of points with a uniform grid.
class PointGrid {
 public:
  PointGrid(const std::vector<glm::vec3>& points, const Aabb& bounds)
      : mPoints(points), mBounds(bounds) {
    const float diagonal = glm::length(bounds.extent());
    mCell = std::max(diagonal / 64.0f, 1e-6f);
    mSize = glm::max(glm::ivec3(glm::ceil(bounds.extent() / mCell)), glm::ivec3(1));
    mCells.resize(size_t(mSize.x) * mSize.y * mSize.z);
    for (uint32_t i = 0; i < points.size(); ++i) mCells[cellIndex(cellOf(points[i]))].push_back(i);
  }

  // Index of the nearest point accepted by `accept`, or UINT32_MAX.
  template <typename Accept>
  uint32_t nearest(const glm::vec3& query, Accept accept) const {
    const glm::ivec3 centre = cellOf(query);
    uint32_t best = UINT32_MAX;
    float bestDistance = std::numeric_limits<float>::max();
    const int maxRing = std::max({mSize.x, mSize.y, mSize.z});
    for (int ring = 0; ring <= maxRing; ++ring) {
      // Points in rings beyond this one are at least (ring − 1) cells away.
      if (best != UINT32_MAX && float(ring - 1) * mCell > std::sqrt(bestDistance)) break;
      for (int z = centre.z - ring; z <= centre.z + ring; ++z) {
        for (int y = centre.y - ring; y <= centre.y + ring; ++y) {
          for (int x = centre.x - ring; x <= centre.x + ring; ++x) {
            if (std::max({std::abs(x - centre.x), std::abs(y - centre.y),
                          std::abs(z - centre.z)}) != ring)
              continue;
            if (x < 0 || y < 0 || z < 0 || x >= mSize.x || y >= mSize.y || z >= mSize.z) continue;
            for (uint32_t i : mCells[cellIndex({x, y, z})]) {
              if (!accept(i)) continue;
              const glm::vec3 d = mPoints[i] - query;
              const float distance = glm::dot(d, d);
              if (distance < bestDistance || (distance == bestDistance && i < best))
                bestDistance = distance, best = i;
            }
          }
        }
      }
    }
    return best;
  }

 private:
  glm::ivec3 cellOf(const glm::vec3& p) const {
    return glm::clamp(glm::ivec3(glm::floor((p - mBounds.min) / mCell)), glm::ivec3(0), mSize - 1);
  }
  size_t cellIndex(const glm::ivec3& c) const {
    return (size_t(c.z) * mSize.y + c.y) * mSize.x + c.x;
  }

  const std::vector<glm::vec3>& mPoints;
  Aabb mBounds;
  float mCell = 1.0f;
  glm::ivec3 mSize{1};
  std::vector<std::vector<uint32_t>> mCells;
};

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

BoxHierarchy woodHierarchy(const Tree& tree) {
  const WoodMesh& wood = tree.wood;
  BoxHierarchy hierarchy;
  hierarchy.source = "wood";
  if (wood.positions.empty()) return hierarchy;
  // Connected parts, numbered by their first vertex; then in order of their lowest point (ties by
  // that number): the trunk first.
  const std::vector<uint32_t> partOf = wood.vertexParts();
  const size_t parts = size_t(*std::max_element(partOf.begin(), partOf.end())) + 1;
  if (parts < 2) return hierarchy;
  std::vector<uint32_t> lowest(parts, UINT32_MAX);
  std::vector<Aabb> partBox(parts);
  for (uint32_t v = 0; v < wood.positions.size(); ++v) {
    const uint32_t p = partOf[v];
    partBox[p].extend(wood.positions[v]);
    if (lowest[p] == UINT32_MAX || wood.positions[v].y < wood.positions[lowest[p]].y) lowest[p] = v;
  }
  std::vector<uint32_t> byHeight(parts);
  std::iota(byHeight.begin(), byHeight.end(), 0u);
  std::stable_sort(byHeight.begin(), byHeight.end(), [&](uint32_t a, uint32_t b) {
    return wood.positions[lowest[a]].y < wood.positions[lowest[b]].y;
  });
  std::vector<uint32_t> rank(parts);
  for (uint32_t i = 0; i < parts; ++i) rank[byHeight[i]] = i;
  Aabb bounds = tree.bounds;
  const PointGrid grid(wood.positions, bounds);
  std::vector<int32_t> partParent(parts, -1);
  for (uint32_t i = 1; i < parts; ++i) {
    const uint32_t p = byHeight[i];
    const uint32_t v =
        grid.nearest(wood.positions[lowest[p]], [&](uint32_t u) { return rank[partOf[u]] < i; });
    partParent[p] = static_cast<int32_t>(partOf[v]);
  }
  // Leaves hang on the part nearest their centre.
  std::vector<uint32_t> leafPart(tree.leaves.size());
  for (size_t l = 0; l < tree.leaves.size(); ++l) {
    leafPart[l] = partOf[grid.nearest(tree.leaves[l].center, [](uint32_t) { return true; })];
  }
  // Nodes in pre-order from the trunk, children in height order.
  std::vector<std::vector<uint32_t>> partChildren(parts);
  for (uint32_t i = 1; i < parts; ++i) partChildren[partParent[byHeight[i]]].push_back(byHeight[i]);
  std::vector<std::vector<uint32_t>> partLeaves(parts);
  for (uint32_t l = 0; l < tree.leaves.size(); ++l) partLeaves[leafPart[l]].push_back(l);
  std::vector<std::pair<uint32_t, int32_t>> stack{{byHeight[0], -1}};
  while (!stack.empty()) {
    const auto [p, parentNode] = stack.back();
    stack.pop_back();
    const auto index = static_cast<int32_t>(hierarchy.nodes.size());
    BoxNode node;
    node.parent = parentNode;
    node.level = parentNode < 0 ? 0 : hierarchy.nodes[parentNode].level + 1;
    node.box = partBox[p];
    node.leafBegin = static_cast<uint32_t>(hierarchy.leafOrder.size());
    for (uint32_t l : partLeaves[p]) {
      hierarchy.leafOrder.push_back(l);
      for (int c = 0; c < 4; ++c) node.box.extend(tree.leaves[l].corner(c));
    }
    node.leafEnd = static_cast<uint32_t>(hierarchy.leafOrder.size());
    if (parentNode >= 0) hierarchy.nodes[parentNode].children.push_back(index);
    hierarchy.nodes.push_back(std::move(node));
    for (auto it = partChildren[p].rbegin(); it != partChildren[p].rend(); ++it)
      stack.emplace_back(*it, index);
  }
  // Subtree leaf ranges and boxes, bottom-up (children follow their parent in pre-order).
  for (size_t n = hierarchy.nodes.size(); n-- > 0;) {
    BoxNode& node = hierarchy.nodes[n];
    node.subtreeLeafEnd = node.leafEnd;
    for (int32_t child : node.children) {
      node.subtreeLeafEnd = std::max(node.subtreeLeafEnd, hierarchy.nodes[child].subtreeLeafEnd);
      node.box.extend(hierarchy.nodes[child].box);
    }
  }
  return hierarchy;
}

void pruneByVolumeRatio(BoxHierarchy& hierarchy, float threshold, uint32_t minLeaves) {
  for (size_t n = 0; n < hierarchy.nodes.size(); ++n) {
    BoxNode& node = hierarchy.nodes[n];
    const bool hasLeaves = node.subtreeLeafEnd - node.leafBegin >= std::max(minLeaves, 1u);
    if (node.parent < 0) {
      node.textured = hasLeaves;
      continue;
    }
    const float parentVolume = hierarchy.nodes[node.parent].box.volume();
    const float ratio = parentVolume > 0.0f ? node.box.volume() / parentVolume : 0.0f;
    node.textured = hasLeaves && ratio >= threshold;
  }
}

std::vector<int32_t> texturedCoarseToFine(const BoxHierarchy& hierarchy) {
  std::vector<int32_t> order;
  for (size_t n = 0; n < hierarchy.nodes.size(); ++n)
    if (hierarchy.nodes[n].textured) order.push_back(static_cast<int32_t>(n));
  const auto leaves = [&](int32_t n) {
    return hierarchy.nodes[n].subtreeLeafEnd - hierarchy.nodes[n].leafBegin;
  };
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
    const BoxNode &x = hierarchy.nodes[a], &y = hierarchy.nodes[b];
    return x.level != y.level ? x.level < y.level : leaves(a) > leaves(b);
  });
  return order;
}

void keepTexturedBoxes(BoxHierarchy& hierarchy, size_t keep) {
  const std::vector<int32_t> order = texturedCoarseToFine(hierarchy);
  for (size_t i = std::max<size_t>(keep, 1); i < order.size(); ++i)
    hierarchy.nodes[order[i]].textured = false;
}

void walkHierarchy(const BoxHierarchy& hierarchy, const std::vector<float>& lodDistance,
                   const glm::vec3& viewer, float transition, int forcedLevel,
                   HierarchyWalk& walk) {
  walk.boxes.clear();
  walk.leafNodes.clear();
  if (hierarchy.nodes.empty()) return;
  struct Item {
    int32_t node;
    float dissolve;  // inherited from a transitioning ancestor: keep below this threshold
  };
  std::vector<Item> stack{{0, 0.0f}};
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    const BoxNode& node = hierarchy.nodes[item.node];
    if (node.subtreeLeafEnd == node.leafBegin) continue;  // nothing to draw below
    const bool inherited = item.dissolve > 0.0f;
    const WalkEntry inheritedEntry{item.node, item.dissolve, true};
    float childDissolve = item.dissolve;
    if (node.textured && forcedLevel < 0) {
      const float distance = glm::length(viewer - node.box.center());
      const float lod = lodDistance[item.node];
      if (distance > lod * (1.0f + transition)) {
        walk.boxes.push_back(inherited ? inheritedEntry : WalkEntry{item.node});
        continue;
      }
      if (distance > lod && !inherited) {
        // In the band: the box fades in as the viewer moves away, the finer level out.
        const float hidden = 1.0f - (distance - lod) / (lod * transition);
        walk.boxes.push_back({item.node, hidden, false});
        childDissolve = hidden;
      }
    } else if (node.textured && forcedLevel >= 0 && node.level >= forcedLevel) {
      walk.boxes.push_back({item.node});
      continue;
    }
    if (node.leafEnd > node.leafBegin) {
      walk.leafNodes.push_back(childDissolve > 0.0f ? WalkEntry{item.node, childDissolve, true}
                                                    : WalkEntry{item.node});
    }
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it)
      stack.push_back({*it, childDissolve});
  }
}

}  // namespace canopy
