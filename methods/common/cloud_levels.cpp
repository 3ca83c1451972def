#include "methods/common/cloud_levels.h"

#include <algorithm>
#include <array>

#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "common/error.h"
#include "methods/method.h"

namespace canopy {

void CloudLevels::addLevel(size_t billboardsBefore, size_t billboards) {
  ranges.push_back(
      {static_cast<uint32_t>(billboardsBefore * 6), static_cast<uint32_t>(billboards * 6)});
}

void CloudLevels::draw(const LodInstances& lod, const std::function<void(size_t level)>& prepare,
                       bool pulled, const GroupFirst& first) const {
  const gl::Api& g = gl::api();
  const auto& instances = lod.ranges();
  for (size_t level = 0; level < instances.size() && level < ranges.size(); ++level) {
    if (instances[level].count == 0) continue;
    if (prepare) prepare(level);
    const std::vector<LodInstances::Range>& groups = lod.groupRanges(level);
    for (size_t group = 0; group < groups.size(); ++group) {
      if (groups[group].count == 0) continue;
      bindInstanceMatrices(lod.buffer(), 4, groups[group].first);
      const GLint start = first ? first(level, group) : static_cast<GLint>(ranges[level].first);
      if (pulled) {
        g.DrawArraysInstanced(GL_TRIANGLES, start, static_cast<GLsizei>(ranges[level].count),
                              groups[group].count);
        continue;
      }
      g.DrawElementsInstanced(
          GL_TRIANGLES, static_cast<GLsizei>(ranges[level].count), GL_UNSIGNED_INT,
          reinterpret_cast<const void*>(sizeof(uint32_t) * size_t(start)), groups[group].count);
    }
  }
}

ShaderLodLevels shaderLodLevels(const CloudLevels& clouds, const std::vector<float>& thresholds,
                                float lowResPixels) {
  ShaderLodLevels out;
  out.draw.treeBounds = clouds.treeBounds;
  out.thresholds = thresholds;
  if (lowResPixels > 0.0f &&
      std::find(thresholds.begin(), thresholds.end(), lowResPixels) == thresholds.end()) {
    out.thresholds.insert(std::find_if(out.thresholds.begin(), out.thresholds.end(),
                                       [&](float t) { return t < lowResPixels; }),
                          lowResPixels);
  }
  out.firstTextureCloud = clouds.ranges.size();
  out.lookupLevels = out.thresholds.size() + 1;
  for (size_t level = 0; level <= out.thresholds.size(); ++level) {
    // The level holds radii in [thresholds[level], thresholds[level − 1]).
    const size_t cloud = level < out.thresholds.size()
                             ? size_t(LodInstances::levelFor(out.thresholds[level], thresholds))
                             : thresholds.size();
    out.draw.ranges.push_back(clouds.ranges[std::min(cloud, clouds.ranges.size() - 1)]);
    const bool texture =
        lowResPixels > 0.0f && level > 0 && out.thresholds[level - 1] <= lowResPixels;
    if (texture && out.lookupLevels > level) {
      out.lookupLevels = level;
      out.firstTextureCloud = std::min(cloud, clouds.ranges.size() - 1);
    }
  }
  return out;
}

ViewOrders CloudLevels::viewOrders(std::span<const glm::vec3> centers, size_t sortedLevels,
                                   int directions) const {
  if (directions <= 0) return {};
  std::vector<ViewOrders::Range> sorted;
  for (size_t level = 0; level < ranges.size() && level < sortedLevels; ++level)
    sorted.push_back({ranges[level].first / 6, ranges[level].count / 6});
  return buildViewOrders(centers, sorted, directions);
}

LodInstances::Grouping CloudLevels::directionGrouping(const ViewOrders& orders,
                                                      const FrameContext& frame,
                                                      size_t sortedLevels) const {
  if (orders.empty()) return {};
  const glm::vec3 centre = treeBounds.center();
  return [&orders, &frame, centre, sortedLevels](int level, const glm::mat4& model) {
    if (size_t(level) >= sortedLevels) return 0;
    const glm::vec3 eye = glm::vec3(glm::inverse(model) * glm::vec4(frame.cameraPosition, 1.0f));
    return orders.nearest(eye - centre);
  };
}

std::vector<uint32_t> CloudLevels::withOrderedIndices(const std::vector<uint32_t>& indices,
                                                      const ViewOrders& orders) {
  std::vector<uint32_t> out = indices;
  out.reserve(indices.size() + 6 * orders.order.size());
  for (uint32_t billboard : orders.order)
    out.insert(out.end(), indices.begin() + 6 * billboard, indices.begin() + 6 * billboard + 6);
  return out;
}

namespace {

// The header part: the tree bounds and each level's (first index, index count).
struct LevelFields {
  Aabb bounds;
  std::vector<std::array<uint32_t, 2>> levels;
  template <class V>
  void visit(V& v) {
    v("bounds", bounds);
    v("levels", levels);
  }
};

}  // namespace

void CloudLevels::save(AssetFolder& asset) const {
  LevelFields fields{treeBounds, {}};
  for (const Range& r : ranges) fields.levels.push_back({r.first, r.count});
  asset.writeFields(fields);
}

void CloudLevels::load(AssetFolder& asset, size_t indexCount) {
  LevelFields fields;
  asset.readFields(fields);
  treeBounds = fields.bounds;
  ranges.clear();
  for (const auto& [first, count] : fields.levels) {
    ranges.push_back({first, count});
    if (size_t(first) + count > indexCount)
      throwInputError("{}: level ranges point past the indices", asset.folder().string());
  }
}

void validateIndices(const std::vector<uint32_t>& indices, size_t vertexCount,
                     const std::string& folder) {
  for (uint32_t index : indices) {
    if (index >= vertexCount) throwInputError("{}: corrupt indices", folder);
  }
}

}  // namespace canopy
