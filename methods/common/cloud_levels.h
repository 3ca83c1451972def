#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/tree.h"
#include "methods/common/lod_instances.h"
#include "methods/method.h"

namespace canopy {

// The geometric levels of detail of a cloud-based method: one index range (6 indices per
// billboard) per cloud in one index buffer, and the tree bounds LoD distances are measured from.
struct CloudLevels {
  struct Range {
    uint32_t first = 0;  // first index
    uint32_t count = 0;  // indices
  };
  std::vector<Range> ranges;
  Aabb treeBounds;

  // Appends a level of `billboards` quads after `billboardsBefore` quads.
  void addLevel(size_t billboardsBefore, size_t billboards);
  // Draws every level's instances with the bound program and vertex array; `prepare(level)` runs
  // before a level's draw (to switch programs), the instance matrices go to locations 4–7.
  // `pulled`: no index buffer; DrawArrays over the same ranges (6 vertices per billboard), the
  // vertex shader finding its billboard and corner from gl_VertexID.
  // With LodInstances groups, one draw per level and group; `firstVertex(level, group)` (pulled
  // draws only) then names where the group's vertices start (the vertex shader maps them to
  // billboards, e.g. through ViewOrders), else the level's range is drawn for every group.
  using FirstVertex = std::function<GLint(size_t level, size_t group)>;
  void draw(const LodInstances& lod, const std::function<void(size_t level)>& prepare,
            bool pulled = false, const FirstVertex& firstVertex = {}) const;

  // The asset header's "bounds" and "levels".
  void save(AssetFolder& asset) const;
  // Reads what save wrote and checks it against the index buffer (or 6 × the billboards, when
  // pulled); InputError naming the asset.
  void load(AssetFolder& asset, size_t indexCount);
};

// InputError naming `folder` when an index points past the vertices.
void validateIndices(const std::vector<uint32_t>& indices, size_t vertexCount,
                     const std::string& folder);

}  // namespace canopy
