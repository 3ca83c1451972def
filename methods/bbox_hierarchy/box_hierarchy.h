#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "common/tree.h"

namespace canopy {

// The bounding-box hierarchy of Lluch, Camahort and Vivó (2004) §3: one node per branch, its box
// bounding the branch and all its children, in pre-order. Leaves are referred to through
// `leafOrder`, in which a node's own leaves are [leafBegin, leafEnd) and its subtree's
// [leafBegin, subtreeLeafEnd).
struct BoxNode {
  int32_t parent = -1;
  std::vector<int32_t> children;
  int32_t level = 0;
  Aabb box;
  uint32_t leafBegin = 0;
  uint32_t leafEnd = 0;
  uint32_t subtreeLeafEnd = 0;
  bool textured = false;  // has six images (level pruning, §3.2.4, decides)
};

struct BoxHierarchy {
  std::vector<BoxNode> nodes;
  std::vector<uint32_t> leafOrder;  // indices into Tree::leaves
  std::string source;               // "branches" (the L-system's PUSH/POP) or "spatial"
};

// The tree's own branch hierarchy (built-in trees: the turtle's PUSH/POP boxes).
BoxHierarchy hierarchyFromBranches(const Tree& tree);
// A branch hierarchy derived from the wood mesh, for models without an L-system: each connected
// part of the wood (shared positions join triangles) is a branch; parts are ordered by their
// lowest point and each hangs on the nearest part that starts lower (so the trunk is the root);
// each leaf hangs on the part nearest its centre. Empty when the wood has fewer than two parts.
BoxHierarchy woodHierarchy(const Tree& tree);
// A hierarchy of the leaves only: boxes split at the median along their longest axis until a box
// holds at most `maxLeaves` leaves. The fallback for models without a branch hierarchy.
BoxHierarchy spatialHierarchy(const Tree& tree, int maxLeaves);

// §3.2.4: a node gets textures only when its box volume over its parent's is at least
// `threshold`; the root always does. Nodes with fewer than `minLeaves` leaves in their subtree get
// none (not in the paper: models with thousands of twig parts would otherwise get thousands of
// boxes whose few leaves are cheaper drawn as polygons).
void pruneByVolumeRatio(BoxHierarchy& hierarchy, float threshold, uint32_t minLeaves = 1);

// The textured boxes in the order they keep their images under a memory bound: coarse levels
// first (§1, §6: progressive transmission), within a level the boxes holding more leaves.
std::vector<int32_t> texturedCoarseToFine(const BoxHierarchy& hierarchy);
// Keeps the images of the first `keep` boxes of texturedCoarseToFine (at least the root's); the
// others become untextured, so the walk opens them. Not in the paper, whose hierarchy has a box
// per branch: with one per branch texture memory would grow with the tree.
void keepTexturedBoxes(BoxHierarchy& hierarchy, size_t keep);

// The walk of Fig. 4 from one viewer (in the tree's frame): a textured box whose distance to
// the viewer exceeds its LoD distance d is drawn as its images and its subtree skipped;
// otherwise its own leaves are drawn as polygons and its children visited. Untextured boxes are
// always opened. Within the band (d, d·(1 + transition)] a box is drawn dissolved together with
// the finer level, on complementary pixels of one dither: the box keeps the dither values at or
// above `threshold`, everything below it keeps those under it (nested transitions inside a
// dissolving subtree switch hard). forcedLevel >= 0 draws, whatever the distance, the first
// textured box at that level or finer on each branch as its images (finer where the box of that
// level has none).
struct WalkEntry {
  int32_t node = 0;
  float threshold = 0.0f;  // 0: drawn whole
  bool keepBelow = false;  // keep dither values below `threshold` (else at or above it)
  // The share of pixels drawn: 1 whole, else the dither's range kept.
  float share() const {
    return threshold <= 0.0f ? 1.0f : keepBelow ? threshold : 1.0f - threshold;
  }
};
struct HierarchyWalk {
  std::vector<WalkEntry> boxes;      // nodes drawn as images
  std::vector<WalkEntry> leafNodes;  // nodes whose own leaves are drawn as polygons
};
void walkHierarchy(const BoxHierarchy& hierarchy, const std::vector<float>& lodDistance,
                   const glm::vec3& viewer, float transition, int forcedLevel, HierarchyWalk& walk);

}  // namespace canopy
