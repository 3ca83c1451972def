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
// bake) adds a second chain, the "residual" levels from `residualFrom` on: the rest of the wood
// and its simplifications, drawn instead of the full chain once the tree's projected radius is
// below `residualBelowPixels` (where those images are drawn).
struct WoodLevels {
  std::vector<uint32_t> indices;
  std::vector<WoodRange> ranges;         // every level's ranges, level by level
  std::vector<uint32_t> rangesPerLevel;  // how many of `ranges` each level has
  std::vector<float> errors;  // each level's largest deviation from its chain's first (world units)
  size_t residualFrom = 0;    // first residual level; 0: no residual chain
  float residualBelowPixels = 0.0f;  // projected radius (output pixels) below which it is drawn

  size_t levels() const { return rangesPerLevel.size(); }
  bool hasResidual() const { return residualFrom > 0; }
  // The index of level `level`'s first range in `ranges`.
  size_t firstRange(size_t level) const;
  uint32_t triangles(size_t level) const;
  // Projected tree radii (output pixels) below which the next coarser level is drawn
  // (LodInstances' thresholds, one per level after the first), so that no level's error spans
  // more than `errorPixels` output pixels: level l + 1 is allowed once its error × radiusPixels /
  // treeRadius <= errorPixels. With a residual chain, the full chain's thresholds stop at
  // residualBelowPixels and the residual chain's start there; a level never drawn gets its
  // successor's threshold, so its range stays empty. Empty: level 0 always.
  std::vector<float> thresholds(float treeRadius, float errorPixels) const;
  // Structural checks after loading: the ranges tile `indices` in order, whole triangles, one
  // error per level, errors that do not fall within a chain.
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

// Appends `residual` to `levels` as its residual chain, drawn below `belowPixels` of projected
// radius.
void appendResidualLevels(WoodLevels& levels, const WoodLevels& residual, float belowPixels);

}  // namespace canopy
