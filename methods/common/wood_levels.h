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
struct WoodLevels {
  std::vector<uint32_t> indices;
  std::vector<WoodRange> ranges;         // every level's ranges, level by level
  std::vector<uint32_t> rangesPerLevel;  // how many of `ranges` each level has
  std::vector<float> errors;  // each level's largest deviation from the full mesh (world units)

  size_t levels() const { return rangesPerLevel.size(); }
  // The index of level `level`'s first range in `ranges`.
  size_t firstRange(size_t level) const;
  uint32_t triangles(size_t level) const;
  // Projected tree radii (output pixels) below which the next coarser level is drawn, so that no
  // level's error spans more than `errorPixels` output pixels (LodInstances' thresholds): level
  // l + 1 is allowed once its error × radiusPixels / treeRadius <= errorPixels.
  std::vector<float> thresholds(float treeRadius, float errorPixels) const;
  // Structural checks after loading: the ranges tile `indices` in order, whole triangles, one
  // error per level, errors that do not fall.
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

}  // namespace canopy
