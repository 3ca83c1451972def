#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace canopy {

// One material's triangles within the wood's index list.
struct WoodRange {
  uint32_t first = 0;  // first index
  uint32_t count = 0;  // indices (3 per triangle)
  uint32_t material = 0;
};

// The wood's levels of detail: level 0 is the full mesh, each further level a copy simplified by
// meshoptimizer's edge collapse (UV and normal seams kept, since it collapses only between
// vertices whose attributes agree) within a larger error. Every level indexes the same vertices;
// their triangles follow one another in `indices`, each level sorted by material.
//
// A method whose images for small trees already hold part of the wood (captured into them at
// bake) adds "residual" chains after the full one: the rest of the wood and its simplifications,
// drawn instead of the chain before once the tree's projected radius is below the chain's
// `belowPixels` (where those images are drawn). A method with several such images (a middle and
// a far cloud) adds one chain per image set, in decreasing `belowPixels`: the smaller the tree,
// the more of its wood the images hold.
struct ResidualChain {
  size_t from = 0;           // the chain's first level
  float belowPixels = 0.0f;  // projected radius (output pixels) below which it is drawn
  template <class V>
  void visit(V& v) {  // as saved assets hold it
    v("from", from);
    v("below_px", belowPixels);
  }
};

// Wood triangles a method's images hold for trees drawn below `belowPixels` of projected radius.
struct CapturedWood {
  std::vector<bool> triangles;  // one flag per wood triangle
  float belowPixels = 0.0f;
};

struct WoodLevels {
  std::vector<uint32_t> indices;
  std::vector<WoodRange> ranges;         // every level's ranges, level by level
  std::vector<uint32_t> rangesPerLevel;  // how many of `ranges` each level has
  std::vector<float> errors;  // each level's largest deviation from its chain's first (world units)
  std::vector<ResidualChain> residualChains;  // in level order; empty: the full chain only

  size_t levels() const { return rangesPerLevel.size(); }
  bool hasResidual() const { return !residualChains.empty(); }
  // Whether `level` belongs to a residual chain.
  bool isResidual(size_t level) const {
    return hasResidual() && level >= residualChains.front().from;
  }
  // The index of level `level`'s first range in `ranges`.
  size_t firstRange(size_t level) const;
  uint32_t triangles(size_t level) const;
  // Projected tree radii (output pixels) below which the next coarser level is drawn
  // (LodInstances' thresholds, one per level after the first), so that no level's error spans
  // more than `errorPixels` output pixels: level l + 1 is allowed once its error × radiusPixels /
  // treeRadius <= errorPixels. With residual chains, each chain's thresholds stay within the
  // radii it is drawn at (below its belowPixels, above the next chain's) and a chain's first
  // level starts at its belowPixels; a level never drawn gets its successor's threshold, so its
  // range stays empty. Empty: level 0 always.
  std::vector<float> thresholds(float treeRadius, float errorPixels) const;
  // Structural checks after loading: the ranges tile `indices` in order, whole triangles, one
  // error per level, errors that do not fall within a chain, chains in order with positive and
  // decreasing belowPixels.
  bool consistent() const;
};

// Level 0 from `indices` / `ranges` (sorted by material), then the simplified levels, their error
// bounds doubling from `finestError` (world units) up to `coarsestError`; a level that removes
// fewer than a sixth of the previous level's triangles is skipped, since it would cost a switch
// and buy almost nothing.
WoodLevels buildWoodLevels(const std::vector<glm::vec3>& positions,
                           const std::vector<uint32_t>& indices,
                           const std::vector<WoodRange>& ranges, float finestError,
                           float coarsestError);

// The residual chain of `full` (no residual chain of its own): each level without the triangles
// whose three corners are all `captured` vertices (every triangle of the full mesh around them
// lies in the method's images). Every simplified level indexes the full mesh's vertices, so the
// residual keeps the full chain's simplification and error bounds; simplifying the residual
// mesh itself would stall at the borders the captured triangles leave.
WoodLevels residualLevels(const WoodLevels& full, const std::vector<bool>& captured);

// Appends `residual` to `levels` as its next residual chain, drawn below `belowPixels` of
// projected radius (below the previous chain's).
void appendResidualLevels(WoodLevels& levels, const WoodLevels& residual, float belowPixels);

}  // namespace canopy
