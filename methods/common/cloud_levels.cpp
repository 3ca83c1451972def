#include "methods/common/cloud_levels.h"

#include "common/error.h"
#include "methods/method.h"

namespace canopy {

void CloudLevels::addLevel(size_t billboardsBefore, size_t billboards) {
  ranges.push_back(
      {static_cast<uint32_t>(billboardsBefore * 6), static_cast<uint32_t>(billboards * 6)});
}

void CloudLevels::draw(const LodInstances& lod,
                       const std::function<void(size_t level)>& prepare) const {
  const gl::Api& g = gl::api();
  const auto& instances = lod.ranges();
  for (size_t level = 0; level < instances.size() && level < ranges.size(); ++level) {
    if (instances[level].count == 0) continue;
    if (prepare) prepare(level);
    bindInstanceMatrices(lod.buffer(), 4, instances[level].first);
    g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(ranges[level].count),
                            GL_UNSIGNED_INT,
                            reinterpret_cast<const void*>(sizeof(uint32_t) * ranges[level].first),
                            instances[level].count);
  }
}

void CloudLevels::save(nlohmann::json& header) const {
  header["bounds"] = {treeBounds.min.x, treeBounds.min.y, treeBounds.min.z,
                      treeBounds.max.x, treeBounds.max.y, treeBounds.max.z};
  header["levels"] = nlohmann::json::array();
  for (const Range& r : ranges) header["levels"].push_back({r.first, r.count});
}

void CloudLevels::load(const nlohmann::json& header, size_t indexCount, const std::string& folder) {
  const auto& b = header.at("bounds");
  treeBounds.min = {b[0], b[1], b[2]};
  treeBounds.max = {b[3], b[4], b[5]};
  ranges.clear();
  for (const auto& r : header.at("levels")) {
    ranges.push_back({r[0], r[1]});
    if (size_t(ranges.back().first) + ranges.back().count > indexCount) {
      throwInputError("{}: level ranges point past the indices", folder);
    }
  }
}

void validateIndices(const std::vector<uint32_t>& indices, size_t vertexCount,
                     const std::string& folder) {
  for (uint32_t index : indices) {
    if (index >= vertexCount) throwInputError("{}: corrupt indices", folder);
  }
}

}  // namespace canopy
