#include "common/tree.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include <glm/geometric.hpp>

#include "common/error.h"

namespace canopy {

void Aabb::extend(const glm::vec3& point) {
  min = glm::min(min, point);
  max = glm::max(max, point);
}

void Aabb::extend(const Aabb& box) {
  if (box.empty()) return;
  min = glm::min(min, box.min);
  max = glm::max(max, box.max);
}

bool Aabb::contains(const glm::vec3& point, float epsilon) const {
  return point.x >= min.x - epsilon && point.y >= min.y - epsilon && point.z >= min.z - epsilon &&
         point.x <= max.x + epsilon && point.y <= max.y + epsilon && point.z <= max.z + epsilon;
}

bool Aabb::contains(const Aabb& box, float epsilon) const {
  return box.empty() || (contains(box.min, epsilon) && contains(box.max, epsilon));
}

float Aabb::volume() const {
  if (empty()) return 0.0f;
  const glm::vec3 e = extent();
  return e.x * e.y * e.z;
}

glm::vec3 Leaf::corner(int i) const {
  static constexpr float kSignU[4] = {-1, 1, 1, -1};
  static constexpr float kSignV[4] = {-1, -1, 1, 1};
  return center + axisU * (kSignU[i] * halfExtents.x) + axisV * (kSignV[i] * halfExtents.y);
}

glm::vec2 Leaf::cornerUv(int i) const {
  static constexpr int kPickU[4] = {0, 1, 1, 0};
  static constexpr int kPickV[4] = {0, 0, 1, 1};
  return {kPickU[i] ? uvMax.x : uvMin.x, kPickV[i] ? uvMax.y : uvMin.y};
}

std::vector<uint32_t> WoodMesh::vertexParts() const {
  // Union-find over vertices with path halving: triangles' corners, then equal positions.
  std::vector<uint32_t> parent(positions.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  const auto join = [&](uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    join(indices[t], indices[t + 1]);
    join(indices[t], indices[t + 2]);
  }
  std::vector<uint32_t> order(positions.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const glm::vec3 &p = positions[a], &q = positions[b];
    return std::tie(p.x, p.y, p.z, a) < std::tie(q.x, q.y, q.z, b);
  });
  for (size_t i = 1; i < order.size(); ++i)
    if (positions[order[i]] == positions[order[i - 1]]) join(order[i], order[i - 1]);
  std::vector<uint32_t> part(positions.size()), number(positions.size(), UINT32_MAX);
  uint32_t parts = 0;
  for (uint32_t v = 0; v < positions.size(); ++v) {
    const uint32_t root = find(v);
    if (number[root] == UINT32_MAX) number[root] = parts++;
    part[v] = number[root];
  }
  return part;
}

float Tree::boundingSphereRadius() const {
  return bounds.empty() ? 0.0f : 0.5f * glm::length(bounds.extent());
}

namespace {

bool isFinite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool isUnit(const glm::vec3& v) {
  return std::abs(glm::length(v) - 1.0f) < 1e-3f;
}

}  // namespace

void finalizeTree(Tree& tree, const std::string& source) {
  const WoodMesh& wood = tree.wood;
  if (wood.normals.size() != wood.positions.size() || wood.uvs.size() != wood.positions.size() ||
      wood.indices.size() % 3 != 0 || wood.materialIds.size() != wood.triangleCount()) {
    throwInputError("{}: inconsistent wood mesh arrays", source);
  }
  for (size_t i = 0; i < wood.positions.size(); ++i) {
    if (!isFinite(wood.positions[i]) || !isFinite(wood.normals[i])) {
      throwInputError("{}: wood vertex {} is not finite", source, i);
    }
  }
  for (uint32_t index : wood.indices) {
    if (index >= wood.positions.size()) throwInputError("{}: wood index out of range", source);
  }
  for (uint16_t id : wood.materialIds) {
    if (id >= tree.woodMaterials.size())
      throwInputError("{}: wood material id out of range", source);
  }
  if (tree.leaves.empty()) throwInputError("{}: the model has no leaves", source);
  if (tree.leafTextures.empty()) throwInputError("{}: the model has no leaf texture", source);
  for (size_t i = 0; i < tree.leaves.size(); ++i) {
    const Leaf& leaf = tree.leaves[i];
    if (!isFinite(leaf.center) || !isFinite(leaf.normal) || !isFinite(leaf.axisU) ||
        !isFinite(leaf.axisV) || !std::isfinite(leaf.halfExtents.x) ||
        !std::isfinite(leaf.halfExtents.y)) {
      throwInputError("{}: leaf {} has a non-finite vertex", source, i);
    }
    if (!isUnit(leaf.normal) || !isUnit(leaf.axisU) || !isUnit(leaf.axisV)) {
      throwInputError("{}: leaf {} has a degenerate frame", source, i);
    }
    if (leaf.texture >= tree.leafTextures.size()) {
      throwInputError("{}: leaf {} names texture {} of {}", source, i, leaf.texture,
                      tree.leafTextures.size());
    }
    if (leaf.branch >= static_cast<int32_t>(tree.branches.size())) {
      throwInputError("{}: leaf {} names branch node {} of {}", source, i, leaf.branch,
                      tree.branches.size());
    }
  }
  for (const LeafTexture& texture : tree.leafTextures) {
    if (texture.front.empty() || texture.back.empty()) {
      throwInputError("{}: leaf texture '{}' has no image", source, texture.name);
    }
  }
  tree.bounds = Aabb{};
  for (const glm::vec3& p : wood.positions) tree.bounds.extend(p);
  for (const Leaf& leaf : tree.leaves) {
    for (int c = 0; c < 4; ++c) tree.bounds.extend(leaf.corner(c));
  }
  if (tree.name.empty()) tree.name = source;
}

void indexLeavesByBranch(Tree& tree) {
  if (tree.branches.empty()) return;
  // Nodes are in pre-order, so sorting leaves by node index makes every subtree contiguous.
  std::stable_sort(tree.leaves.begin(), tree.leaves.end(),
                   [](const Leaf& a, const Leaf& b) { return a.branch < b.branch; });
  for (BranchNode& node : tree.branches) node.leafBegin = node.leafEnd = 0;
  uint32_t index = 0;
  for (size_t n = 0; n < tree.branches.size(); ++n) {
    BranchNode& node = tree.branches[n];
    node.leafBegin = index;
    while (index < tree.leaves.size() && tree.leaves[index].branch == static_cast<int32_t>(n)) {
      for (int c = 0; c < 4; ++c) node.bounds.extend(tree.leaves[index].corner(c));
      ++index;
    }
    node.leafEnd = index;
  }
  // Children follow their parent in pre-order: walk backwards to close subtrees bottom-up.
  for (size_t n = tree.branches.size(); n-- > 0;) {
    BranchNode& node = tree.branches[n];
    node.subtreeLeafEnd = node.leafEnd;
    for (int32_t child : node.children) {
      node.subtreeLeafEnd = std::max(node.subtreeLeafEnd, tree.branches[child].subtreeLeafEnd);
      node.bounds.extend(tree.branches[child].bounds);
    }
  }
}

}  // namespace canopy
