#include "methods/common/wood_levels.h"

#include <algorithm>
#include <limits>
#include <numeric>

#include <meshoptimizer.h>

namespace canopy {

size_t WoodLevels::firstRange(size_t level) const {
  return std::accumulate(rangesPerLevel.begin(), rangesPerLevel.begin() + long(level), size_t(0));
}

std::vector<float> WoodLevels::thresholds(float treeRadius, float errorPixels) const {
  std::vector<float> result;
  // Below this radius a level's error spans at most errorPixels (never, with errorPixels 0).
  const auto allowedBelow = [&](size_t level) {
    return errorPixels <= 0.0f ? 0.0f : errorPixels * treeRadius / std::max(errors[level], 1e-12f);
  };
  if (!hasResidual()) {
    if (errorPixels <= 0.0f) return result;  // the full mesh always
    for (size_t level = 1; level < levels(); ++level) result.push_back(allowedBelow(level));
    return result;
  }
  // Chain c (0: the full one) is drawn between `above` and `below` pixels of projected radius.
  size_t chain = 0;
  for (size_t level = 1; level < levels(); ++level) {
    const bool first = chain < residualChains.size() && level == residualChains[chain].from;
    if (first) ++chain;
    const float below =
        chain == 0 ? std::numeric_limits<float>::max() : residualChains[chain - 1].belowPixels;
    const float above = chain < residualChains.size() ? residualChains[chain].belowPixels : 0.0f;
    result.push_back(first ? below : std::clamp(allowedBelow(level), above, below));
  }
  return result;
}

uint32_t WoodLevels::triangles(size_t level) const {
  const size_t begin = firstRange(level);
  uint32_t count = 0;
  for (size_t r = begin; r < begin + rangesPerLevel[level]; ++r) count += ranges[r].count / 3;
  return count;
}

bool WoodLevels::consistent() const {
  if (errors.size() != levels() || firstRange(levels()) != ranges.size()) return false;
  size_t next = 0;  // every level's triangles follow the previous level's
  for (const WoodRange& range : ranges) {
    if (range.first != next || range.count % 3 != 0) return false;
    next += range.count;
  }
  if (next != indices.size()) return false;
  size_t previousFrom = 0;
  float previousBelow = std::numeric_limits<float>::infinity();
  for (const ResidualChain& chain : residualChains) {
    if (chain.from <= previousFrom || chain.from >= levels() || !(chain.belowPixels > 0.0f) ||
        !(chain.belowPixels < previousBelow))
      return false;
    previousFrom = chain.from;
    previousBelow = chain.belowPixels;
  }
  const auto chainStart = [&](size_t level) {
    return std::any_of(residualChains.begin(), residualChains.end(),
                       [&](const ResidualChain& chain) { return chain.from == level; });
  };
  for (size_t level = 1; level < levels(); ++level) {
    if (!chainStart(level) && !(errors[level] >= errors[level - 1])) return false;
  }
  return true;
}

namespace {

// One material range simplified within `relativeError` (meshoptimizer's error relative to the
// mesh scale) into `out`, returning its index count. The edge-collapse simplifier keeps the
// topology, so a wood of many separate tubes stalls at a few triangles per tube; where the
// vertex-clustering ("sloppy") simplifier, which may merge and remove parts, gets fewer triangles
// within the same bound, its result is taken.
size_t simplifyRange(std::vector<uint32_t>& out, const std::vector<glm::vec3>& positions,
                     const uint32_t* indices, uint32_t count, float relativeError) {
  out.resize(count);
  const float* xyz = &positions[0].x;
  // Target 0 triangles: collapse until the next collapse would exceed the error bound.
  size_t kept = meshopt_simplify(out.data(), indices, count, xyz, positions.size(),
                                 sizeof(glm::vec3), 0, relativeError);
  std::vector<uint32_t> sloppy(count);
  // Ever smaller targets, a sixth fewer triangles each: the clustering's error does not grow
  // monotonically with the reduction, so every target is tried and the fewest triangles within
  // the bound win.
  for (size_t target = kept / 18 * 15; target >= 3; target = target / 18 * 15) {
    float error = 0.0f;
    // Its own error limit stops it far short of what it reaches within the bound (2,409 instead
    // of 880 triangles on broadleaf at 2.5 %), so the target alone drives it and the bound is
    // checked on the result.
    const size_t got = meshopt_simplifySloppy(sloppy.data(), indices, count, xyz, positions.size(),
                                              sizeof(glm::vec3), target, 1.0f, &error);
    if (got >= kept || error > relativeError) continue;
    std::copy(sloppy.begin(), sloppy.begin() + long(got), out.begin());
    kept = got;
  }
  return kept;
}

// One level: each material range of the full mesh simplified within `relativeError`, its
// ranges starting from index 0 of its own `indices`.
struct SimplifiedLevel {
  std::vector<uint32_t> indices;
  std::vector<WoodRange> ranges;
};

SimplifiedLevel simplifyLevel(const std::vector<glm::vec3>& positions,
                              const std::vector<uint32_t>& indices,
                              const std::vector<WoodRange>& ranges, float relativeError) {
  SimplifiedLevel level;
  std::vector<uint32_t> simplified;
  for (const WoodRange& range : ranges) {
    const size_t count = simplifyRange(simplified, positions, indices.data() + range.first,
                                       range.count, relativeError);
    if (count == 0) continue;  // the whole material vanished within the error
    level.ranges.push_back({uint32_t(level.indices.size()), uint32_t(count), range.material});
    level.indices.insert(level.indices.end(), simplified.begin(), simplified.begin() + long(count));
  }
  return level;
}

}  // namespace

WoodLevels buildWoodLevels(const std::vector<glm::vec3>& positions,
                           const std::vector<uint32_t>& indices,
                           const std::vector<WoodRange>& ranges, float finestError,
                           float coarsestError) {
  WoodLevels levels;
  levels.indices = indices;
  levels.ranges = ranges;
  levels.rangesPerLevel = {uint32_t(ranges.size())};
  levels.errors = {0.0f};
  if (positions.empty() || indices.empty() || finestError <= 0.0f) return levels;
  const float scale = meshopt_simplifyScale(&positions[0].x, positions.size(), sizeof(glm::vec3));
  if (!(scale > 0.0f)) return levels;
  size_t previous = indices.size();  // indices of the last level kept
  for (float bound = finestError; bound <= coarsestError * 1.0001f && previous > 0; bound *= 2.0f) {
    const SimplifiedLevel level = simplifyLevel(positions, indices, ranges, bound / scale);
    if (uint64_t(level.indices.size()) * 6 > uint64_t(previous) * 5) continue;  // does not pay
    const auto offset = uint32_t(levels.indices.size());
    for (WoodRange range : level.ranges) {
      range.first += offset;
      levels.ranges.push_back(range);
    }
    levels.indices.insert(levels.indices.end(), level.indices.begin(), level.indices.end());
    levels.rangesPerLevel.push_back(uint32_t(level.ranges.size()));
    levels.errors.push_back(bound);  // the bound meshoptimizer kept every collapse within
    previous = level.indices.size();
  }
  return levels;
}

WoodLevels residualLevels(const WoodLevels& full, const std::vector<bool>& captured) {
  WoodLevels residual;
  residual.errors = full.errors;
  for (size_t level = 0; level < full.levels(); ++level) {
    const size_t begin = full.firstRange(level);
    uint32_t ranges = 0;
    for (size_t r = begin; r < begin + full.rangesPerLevel[level]; ++r) {
      const WoodRange& range = full.ranges[r];
      WoodRange kept{uint32_t(residual.indices.size()), 0, range.material};
      for (uint32_t i = range.first; i < range.first + range.count; i += 3) {
        const uint32_t* corner = &full.indices[i];
        if (captured[corner[0]] && captured[corner[1]] && captured[corner[2]]) continue;
        residual.indices.insert(residual.indices.end(), corner, corner + 3);
        kept.count += 3;
      }
      if (kept.count == 0) continue;
      residual.ranges.push_back(kept);
      ++ranges;
    }
    residual.rangesPerLevel.push_back(ranges);
  }
  return residual;
}

void appendResidualLevels(WoodLevels& levels, const WoodLevels& residual, float belowPixels) {
  levels.residualChains.push_back({levels.levels(), belowPixels});
  const auto offset = uint32_t(levels.indices.size());
  for (WoodRange range : residual.ranges) {
    range.first += offset;
    levels.ranges.push_back(range);
  }
  levels.indices.insert(levels.indices.end(), residual.indices.begin(), residual.indices.end());
  levels.rangesPerLevel.insert(levels.rangesPerLevel.end(), residual.rangesPerLevel.begin(),
                               residual.rangesPerLevel.end());
  levels.errors.insert(levels.errors.end(), residual.errors.begin(), residual.errors.end());
}

}  // namespace canopy
