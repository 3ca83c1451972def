#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/tree.h"
#include "methods/common/lod_instances.h"
#include "methods/common/view_orders.h"
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
  // With LodInstances groups, one draw per level and group; `first(level, group)` then names
  // where the group's draw starts (a vertex when pulled, whose shader maps it to a billboard;
  // else an index, e.g. into withOrderedIndices), else the level's range is drawn for every group.
  using GroupFirst = std::function<GLint(size_t level, size_t group)>;
  void draw(const LodInstances& lod, const std::function<void(size_t level)>& prepare,
            bool pulled = false, const GroupFirst& first = {}) const;

  // The first `sortedLevels` levels' billboards (`centers`: every billboard's tree-local centre)
  // sorted front to back for `directions` view directions (view_orders.h); empty for 0.
  ViewOrders viewOrders(std::span<const glm::vec3> centers, size_t sortedLevels,
                        int directions) const;
  // LodInstances grouping by view direction: instances of the first `sortedLevels` levels go to
  // the direction of `orders` nearest their view of the tree, the others to group 0. Empty
  // (no grouping) when `orders` is. Holds references to `orders` and `frame`.
  LodInstances::Grouping directionGrouping(const ViewOrders& orders, const FrameContext& frame,
                                           size_t sortedLevels) const;
  // Indexed clouds: `indices` followed, per direction of `orders`, by the sorted levels' six
  // indices per billboard in that direction's order. Level l's group g then starts at index
  // indices.size() + 6 × orders.firstSlot(g, l).
  static std::vector<uint32_t> withOrderedIndices(const std::vector<uint32_t>& indices,
                                                  const ViewOrders& orders);

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
