#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "common/image.h"
#include "methods/volumetric_opacity/opacity_grid.h"

namespace canopy {

// The half extents (world units) of a cell's billboard seen with image axes `right` and `up`:
// the bounding rectangle of the cube's projection (orthographic approximation), so the billboard
// covers what the cell covers from that direction (§6 "projected region R of cell c").
glm::vec2 billboardHalfExtents(float cellSize, const glm::vec3& right, const glm::vec3& up);

inline constexpr uint32_t kNoTile = 0xffffffffu;

// How a view's pixels become billboard texels.
enum class TexelSelection {
  // Each pixel's opacity α_p is split among the cells its ray crosses, in proportion to each
  // cell's optical depth along the ray (−log t_c · length), so compositing the cells' texels in
  // depth order gives back α_p exactly: a_c = 1 − t_p^(e_c / Σe). Every texel of a billboard
  // takes the share of the pixel under it (our change; docs/METHODS.md).
  kPartition,
  // §6 as published: front to back, each billboard keeps ⌊α_c·M²⌋ texels chosen by age then
  // importance, carrying α_p, the pixels it took removed and inpainted.
  kPaper,
};

// Per input view and cell an M×M RGBA texture (§6), the empty and hidden ones dropped:
// tile[view·cells + cell] indexes rgba (M²·4 bytes a tile: sRGB colour, linear alpha; texels
// without alpha carry the tile's mean colour so bilinear filtering does not darken edges). Tiles
// are stored cell by cell, each cell's in view order.
struct ViewTextures {
  int texels = 0;  // M
  int views = 0;
  int cells = 0;
  std::vector<uint32_t> tile;  // views × cells, kNoTile when the texture was dropped
  std::vector<uint8_t> rgba;   // tiles × M² × 4, texel rows from the billboard's top
  size_t emptyTiles = 0;       // dropped: no texel with alpha
  size_t hiddenTiles = 0;      // dropped: every texel behind cells that hide it (hiddenCutoff)
  size_t tileCount() const { return rgba.size() / (size_t(texels) * texels * 4); }
};

struct TextureSettings {
  int texels = 8;  // M (§6: 4 or 8)
  TexelSelection selection = TexelSelection::kPartition;
  // kPartition: a texture is dropped when no texel's contribution after the cells in front of it
  // along the view's rays (a_c · Π_front (1 − a)) exceeds this.
  float hiddenCutoff = 0.02f;
  // kPartition: weight of a cell's share by exp(−frontEmphasis · optical depth in front of it),
  // so a pixel's alpha goes more to the first cells its ray meets (0: by optical depth alone).
  float frontEmphasis = 0.0f;
  bool inpaint = true;    // kPaper: refill the pixels a billboard took from their neighbours
  int inpaintRadius = 2;  // pixels
};

// The billboards' textures of every input view (each view in parallel, each deterministic).
// kPaper follows §6, Fig. 8 and its pseudo-code: per input view, cells front to back; N_curr per
// pixel from a count of the billboards covering it; importance H_t = 1 / (t_curr − t_c^N_curr);
// texels ordered by age then importance; the first ⌊α_c·M²⌋ selected; t_curr /= t_c under
// selected pixels, which are removed from the copy of the image and refilled.
ViewTextures generateViewTextures(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                                  const TextureSettings& settings);

// The selection step of kPaper for one billboard: the indices of the texels to keep, given each
// texel's age and importance, for a cell of transparency tc (exposed for tests).
std::vector<int> selectTexels(const std::vector<uint16_t>& ages,
                              const std::vector<float>& importance, float tc);

// Tiles laid out in square pages of an array texture: tile i is on page i / tilesPerPage, at
// column (i mod tilesPerPage) mod tilesPerRow and row (i mod tilesPerPage) / tilesPerRow.
struct TileAtlas {
  int texels = 0;       // M
  int pageSize = 0;     // texels per side of a page (a multiple of 4, for block compression)
  int tilesPerRow = 0;  // pageSize / M
  std::vector<ImageRgba8> pages;
  int tilesPerPage() const { return tilesPerRow * tilesPerRow; }
};
// The smallest power-of-two page up to maxPageSize holding every tile on one page, or pages of
// maxPageSize. `rgba` holds tiles × M² × 4 bytes.
TileAtlas layOutTiles(const std::vector<uint8_t>& rgba, int texels, int maxPageSize);

}  // namespace canopy
