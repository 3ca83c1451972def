#include "methods/volumetric_opacity/volumetric_levels.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <numeric>

#include <glm/geometric.hpp>

namespace canopy {

std::vector<glm::vec3> orderDirections() {
  std::vector<glm::vec3> directions;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x || y || z) directions.push_back(glm::normalize(glm::vec3(x, y, z)));
  return directions;
}

size_t nearestOrder(const glm::vec3& direction) {
  static const std::vector<glm::vec3> directions = orderDirections();
  size_t best = 0;
  for (size_t d = 1; d < directions.size(); ++d)
    if (glm::dot(directions[d], direction) > glm::dot(directions[best], direction)) best = d;
  return best;
}

void buildOrders(VolumetricLevel& level) {
  const std::vector<glm::vec3> directions = orderDirections();
  const OpacityGrid& grid = level.grid;
  const size_t n = grid.cells.size();
  level.orders.assign(directions.size() * n, 0);
  std::vector<float> key(n);
  for (size_t d = 0; d < directions.size(); ++d) {
    for (size_t c = 0; c < n; ++c) key[c] = glm::dot(grid.cellCenter(c), directions[d]);
    auto begin = level.orders.begin() + std::ptrdiff_t(d * n);
    std::iota(begin, begin + std::ptrdiff_t(n), 0u);
    // Farthest from a viewer along +direction first.
    std::stable_sort(begin, begin + std::ptrdiff_t(n),
                     [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
  }
}

PackedOrders packOrders(const std::vector<VolumetricLevel>& levels) {
  PackedOrders packed;
  packed.sixteenBit = std::all_of(levels.begin(), levels.end(), [](const VolumetricLevel& level) {
    return level.grid.cells.size() <= 65536;
  });
  size_t elements = 0;
  std::vector<uint32_t> values;
  for (const VolumetricLevel& level : levels) {
    packed.levelOffsets.push_back(elements);
    const size_t n = level.grid.cells.size();
    values.insert(values.end(), level.orders.begin(),
                  level.orders.begin() + std::ptrdiff_t(PackedOrders::kStoredDirections * n));
    elements += PackedOrders::kStoredDirections * n;
  }
  if (!packed.sixteenBit) {
    packed.words = std::move(values);
    return packed;
  }
  packed.words.assign((values.size() + 1) / 2, 0);
  for (size_t i = 0; i < values.size(); ++i) packed.words[i / 2] |= values[i] << (16 * (i % 2));
  return packed;
}

std::pair<size_t, bool> PackedOrders::lookup(size_t level, size_t direction, size_t cells) const {
  const bool reversed = direction >= kStoredDirections;
  const size_t stored = reversed ? size_t(kOrderDirections) - 1 - direction : direction;
  return {levelOffsets[level] + stored * cells, reversed};
}

uint32_t PackedOrders::cellAt(size_t first, bool reversed, size_t cells, size_t position) const {
  const size_t i = first + (reversed ? cells - 1 - position : position);
  return sixteenBit ? (words[i / 2] >> (16 * (i % 2))) & 0xffffu : words[i];
}

std::vector<uint32_t> compactTileTable(const std::vector<uint32_t>& tileOfViewCell, size_t views,
                                       size_t cells, uint32_t first) {
  const size_t stride = tableStride(views);
  std::vector<uint32_t> table(cells * stride, 0);
  for (size_t c = 0; c < cells; ++c) {
    uint32_t lowest = kNoTile;
    for (size_t v = 0; v < views; ++v) {
      const uint32_t t = tileOfViewCell[v * cells + c];
      if (t == kNoTile) continue;
      lowest = std::min(lowest, t);
      table[c * stride + 1 + v / 32] |= 1u << (v % 32);
    }
    table[c * stride] = lowest == kNoTile ? 0 : lowest + first;
  }
  return table;
}

uint32_t tileOf(const std::vector<uint32_t>& table, size_t views, size_t view, size_t cell) {
  const size_t stride = tableStride(views), base = cell * stride;
  const uint32_t mask = table[base + 1 + view / 32], bit = uint32_t(view % 32);
  if (!((mask >> bit) & 1u)) return kNoTile;
  uint32_t index = table[base];
  for (size_t w = 0; w < view / 32; ++w) index += uint32_t(std::popcount(table[base + 1 + w]));
  return index + uint32_t(std::popcount(mask & ((1u << bit) - 1u)));
}

size_t tilesClaimed(const std::vector<uint32_t>& table, size_t views, size_t cell) {
  const size_t stride = tableStride(views);
  size_t count = 0;
  for (size_t w = 1; w < stride; ++w) count += size_t(std::popcount(table[cell * stride + w]));
  return count;
}

size_t VolumetricModel::tileCount() const {
  const size_t tileBytes = size_t(atlas.texels) * atlas.texels * 4;
  return tileBytes ? tiles.size() / tileBytes : 0;
}

uint64_t VolumetricModel::textureBytes() const {
  uint64_t bytes = 0;
  if (compression != Compression::kNone) {
    for (const std::vector<uint8_t>& page : compressedPages) bytes += page.size();
  } else {
    for (const ImageRgba8& page : atlas.pages) bytes += page.pixels.size();
  }
  return bytes;
}

void buildAtlas(VolumetricModel& model, int texels, int maxPageSize) {
  model.atlas = layOutTiles(model.tiles, texels, maxPageSize);
  model.compressedPages.clear();
  if (model.compression == Compression::kNone) return;
  model.compressedPages.resize(model.atlas.pages.size());
  tbb::parallel_for(size_t(0), model.atlas.pages.size(), [&](size_t p) {
    model.compressedPages[p] = compressImage(model.atlas.pages[p], model.compression);
  });
}

VolumetricModel buildVolumetricModel(OpacityGrid finest, const std::vector<OpacityView>& views,
                                     const LevelSettings& settings, float minTransparency) {
  VolumetricModel model;
  model.compression = settings.compression;
  // The grid's own level, then coarser ones while they stay at level 2 or finer (§7's grid reaches
  // level 4–5; level 1 has at most 27 cells, too coarse to draw a crown).
  model.levels.push_back({std::move(finest)});
  while (int(model.levels.size()) < settings.levels && model.levels.back().grid.level > 2)
    model.levels.push_back({coarsenGrid(model.levels.back().grid, minTransparency)});
  for (VolumetricLevel& level : model.levels) {
    const ViewTextures textures = generateViewTextures(level.grid, views, settings.textures);
    const auto first =
        uint32_t(model.tiles.size() / (size_t(textures.texels) * textures.texels * 4));
    level.table =
        compactTileTable(textures.tile, size_t(textures.views), size_t(textures.cells), first);
    model.tiles.insert(model.tiles.end(), textures.rgba.begin(), textures.rgba.end());
    level.emptyTiles = textures.emptyTiles;
    level.hiddenTiles = textures.hiddenTiles;
    buildOrders(level);
    spdlog::info(
        "volumetric_opacity: level {}: {} cells, {} textures kept of {} ({} empty, {} hidden)",
        level.grid.level, level.grid.cells.size(), textures.tileCount(), textures.tile.size(),
        textures.emptyTiles, textures.hiddenTiles);
  }
  buildAtlas(model, settings.textures.texels, settings.maxPageSize);
  return model;
}

}  // namespace canopy
