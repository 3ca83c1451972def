#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "methods/volumetric_opacity/opacity_grid.h"

namespace canopy {

// The half extents (world units) of a cell's billboard seen with image axes `right` and `up`:
// the bounding rectangle of the cube's projection (orthographic approximation), so the billboard
// covers what the cell covers from that direction (§6 "projected region R of cell c").
glm::vec2 billboardHalfExtents(float cellSize, const glm::vec3& right, const glm::vec3& up);

inline constexpr uint32_t kNoTile = 0xffffffffu;

// Per input view and cell an M×M RGBA texture (§6), the empty ones dropped: tile[view·cells +
// cell] indexes alpha (M² bytes) and rgb (M²·3 bytes, sRGB) of the non-empty textures.
struct ViewTextures {
  int texels = 0;  // M
  int views = 0;
  int cells = 0;
  std::vector<uint32_t> tile;  // views × cells, kNoTile when the texture has no opaque texel
  std::vector<uint8_t> alpha;  // tiles × M²
  std::vector<uint8_t> rgb;    // tiles × M² × 3
  size_t tileCount() const { return alpha.size() / (size_t(texels) * texels); }
};

struct TextureSettings {
  int texels = 8;         // M (§6: 4 or 8)
  bool inpaint = true;    // refill the pixels a billboard took from their neighbours (OpenCV)
  int inpaintRadius = 2;  // pixels
};

// §6, Fig. 8 and the pseudo-code: per input view, cells front to back; N_curr per pixel from a
// count of the billboards covering it; importance H_t = 1 / (t_curr − t_c^N_curr); texels ordered
// by age then importance; the first ⌊α_c·M²⌋ selected; t_curr /= t_c under selected pixels, which
// are removed from the copy of the image and refilled; ages of the others incremented. Views run
// in parallel, each deterministic.
ViewTextures generateViewTextures(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                                  const TextureSettings& settings);

// The selection step for one billboard: the indices of the texels to keep, given each texel's
// age and importance, for a cell of transparency tc (exposed for tests).
std::vector<int> selectTexels(const std::vector<uint16_t>& ages,
                              const std::vector<float>& importance, float tc);

// §6 packing: alpha kept per texture; two textures share one RGB slot when their alphas do not
// intersect.
struct PackedTextures {
  int texels = 0;
  std::vector<uint32_t> tile;        // as ViewTextures::tile
  std::vector<uint8_t> alpha;        // tiles × M²
  std::vector<uint32_t> slotOfTile;  // tiles
  std::vector<uint8_t> slotRgb;      // slots × M² × 3
  size_t slotCount() const { return slotRgb.size() / (size_t(texels) * texels * 3); }
  size_t texelBytes() const { return alpha.size() + slotRgb.size(); }
};
PackedTextures packTextures(const ViewTextures& textures);

}  // namespace canopy
