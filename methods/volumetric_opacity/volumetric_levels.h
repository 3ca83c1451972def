#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "methods/common/dxt.h"
#include "methods/volumetric_opacity/opacity_grid.h"
#include "methods/volumetric_opacity/view_textures.h"

namespace canopy {

// One level of detail of the recursive grid (§7): its cells, their view textures and their
// back-to-front orders. Level 0 of a model is the finest grid; each next one is 3× coarser.
struct VolumetricLevel {
  OpacityGrid grid;
  // Per cell, tableStride words: the index of its first tile in the model's tiles, then a mask of
  // the views that have a texture (bit v of word 1 + v / 32). The cell's tile of view v is
  // first + the number of mask bits below v (tiles are stored cell by cell in view order).
  std::vector<uint32_t> table;
  std::vector<uint32_t> orders;  // kOrderDirections × cells, back to front per direction
  size_t emptyTiles = 0;         // (cell, view) textures dropped: no texel with alpha
  size_t hiddenTiles = 0;        // dropped: hidden behind the cells in front (hidden cutoff)
};

// Words per cell of VolumetricLevel::table for `views` input views.
inline size_t tableStride(size_t views) {
  return 1 + (views + 31) / 32;
}
// The compact table from a views × cells table of tile indices (kNoTile: none) whose tiles are
// stored cell by cell in view order; `first` is added to every index.
std::vector<uint32_t> compactTileTable(const std::vector<uint32_t>& tileOfViewCell, size_t views,
                                       size_t cells, uint32_t first);
// The tile of (view, cell), or kNoTile: what the vertex shader computes.
uint32_t tileOf(const std::vector<uint32_t>& table, size_t views, size_t view, size_t cell);
// Tiles the table's masks claim (the load checks them against the tiles stored).
size_t tilesClaimed(const std::vector<uint32_t>& table, size_t views, size_t cell);

// The 26 directions (faces, edges and corners of a cube) the cells are sorted along: a draw
// uses the one nearest its viewing direction.
inline constexpr int kOrderDirections = 26;
std::vector<glm::vec3> orderDirections();
size_t nearestOrder(const glm::vec3& direction);
// Fills level.orders from level.grid.
void buildOrders(VolumetricLevel& level);

// The orders as the GPU holds them. Direction d's opposite is 25 − d (orderDirections lists the
// cube's neighbours lexicographically), and its order sorts by the negated key, so it is d's
// order walked backwards: only the first 13 directions are stored. Cell indices are 16-bit, two
// to a word, when every level has at most 65,536 cells. A quarter of the 26 × 32-bit orders.
struct PackedOrders {
  static constexpr size_t kStoredDirections = kOrderDirections / 2;
  std::vector<uint32_t> words;
  bool sixteenBit = false;
  std::vector<size_t> levelOffsets;  // each level's first element (16-bit units when packed)

  // Where a draw along order `direction` finds its cells: the stored order's first element
  // and whether it is walked backwards.
  std::pair<size_t, bool> lookup(size_t level, size_t direction, size_t cells) const;
  // The cell at `position` (0: farthest from the viewer) of that draw: what the shader computes.
  uint32_t cellAt(size_t first, bool reversed, size_t cells, size_t position) const;
};
PackedOrders packOrders(const std::vector<VolumetricLevel>& levels);

// Everything a draw reads: the levels and every level's tiles in one atlas.
struct VolumetricModel {
  std::vector<VolumetricLevel> levels;
  std::vector<glm::vec3> cameraDirections;  // unit, from the grid centre to each input camera
  std::vector<glm::vec3> cameraRight;       // unit image axes of each input camera
  std::vector<glm::vec3> cameraUp;
  std::vector<uint8_t> tiles;  // every level's tiles, M² × 4 bytes each (the CPU copy saved)
  TileAtlas atlas;             // the tiles on pages
  Compression compression = Compression::kNone;
  std::vector<std::vector<uint8_t>> compressedPages;  // S3TC blocks per page, when compressed

  size_t tileCount() const;
  uint64_t textureBytes() const;  // the atlas as uploaded (compressed or RGBA8)
};

// Settings of the levels and their textures.
struct LevelSettings {
  int levels = 3;  // levels of detail wanted (the grid's own and coarser ones down to level 2)
  TextureSettings textures;
  Compression compression = Compression::kDxt5;
  int maxPageSize = 2048;  // texels per side of an atlas page
};

// Builds the levels from the solved finest grid: coarser grids by coarsenGrid, each level's
// textures from the same views, all tiles laid out in the atlas (and compressed).
VolumetricModel buildVolumetricModel(OpacityGrid finest, const std::vector<OpacityView>& views,
                                     const LevelSettings& settings, float minTransparency);

// Lays out (and compresses) model.atlas from model.tiles: used by the bake and by a load.
void buildAtlas(VolumetricModel& model, int texels, int maxPageSize);

}  // namespace canopy
