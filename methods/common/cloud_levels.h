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

// The draw levels of a cloud family whose trees spanning fewer than `lowResPixels` output pixels
// of radius draw their cloud's low-resolution texture instead of its per-fragment lookup (the
// multi-layer paper's shader level of detail, §5.1): the clouds' thresholds with lowResPixels
// among them; each draw level draws one cloud's range, as a lookup (the first `lookupLevels`,
// which are the clouds' own first levels) or as a texture (the rest). lowResPixels 0: none.
struct ShaderLodLevels {
  CloudLevels draw;               // one range per draw level; a cloud split by lowResPixels twice
  std::vector<float> thresholds;  // of the draw levels, for LodInstances::update
  size_t lookupLevels = 0;        // draw levels before the first texture-only one
  size_t firstTextureCloud = 0;   // the finest cloud a texture-only level draws (or the count)
};
ShaderLodLevels shaderLodLevels(const CloudLevels& clouds, const std::vector<float>& thresholds,
                                float lowResPixels);

// InputError naming `folder` when an index points past the vertices.
void validateIndices(const std::vector<uint32_t>& indices, size_t vertexCount,
                     const std::string& folder);

}  // namespace canopy
