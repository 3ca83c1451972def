#include "methods/multilayer_indirect/layered_billboard.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "methods/common/ambient_occlusion.h"

namespace canopy {

SpriteRule parseSpriteRule(const std::string& name) {
  if (name == "paper") return SpriteRule::kPaper;
  if (name == "bounds") return SpriteRule::kBounds;
  throwInputError(R"(parameter 'sprite' = '{}' must be "paper" or "bounds")", name);
}

uint32_t otherSideImage(uint32_t image, const OrientationBins& bins) {
  const uint32_t perSide = uint32_t(bins.tilts * bins.rotations);
  const bool back = (image / perSide) % 2 == 1;
  return back ? image - perSide : image + perSide;
}

LayerEntry leafSprite(const Leaf& leaf, const Billboard& billboard, SpriteRule rule) {
  LayerEntry entry;
  entry.position = billboard.toPlane(leaf.center);
  entry.depth = glm::dot(leaf.center - billboard.center, billboard.normal);
  if (rule == SpriteRule::kBounds) {
    entry.size = 2.0f * std::max(leaf.halfExtents.x, leaf.halfExtents.y);
  } else {
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
    for (int c = 0; c < 4; ++c) {
      const glm::vec2 p = billboard.toPlane(leaf.corner(c));
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    // leaf_pixels = area(leaf box) · billboard_pixels / area(billboard); width = sqrt(leaf_pixels),
    // which in plane units is the square root of the box's area.
    entry.size = std::sqrt(std::max((hi.x - lo.x) * (hi.y - lo.y), 1e-12f));
  }
  return entry;
}

LayeredBillboard buildLayeredBillboard(const Tree& tree, const Billboard& billboard,
                                       const LayeringParams& params,
                                       const std::vector<glm::vec4>* cornerOcclusion) {
  LayeredBillboard layered;
  const float longer = 2.0f * std::max(billboard.halfExtents.x, billboard.halfExtents.y);
  const float target = longer / float(params.hashResolution);
  layered.cells = {
      std::max(1, static_cast<int>(std::lround(2.0f * billboard.halfExtents.x / target))),
      std::max(1, static_cast<int>(std::lround(2.0f * billboard.halfExtents.y / target)))};
  layered.cellSize = 2.0f * billboard.halfExtents / glm::vec2(layered.cells);
  const size_t cellCount = size_t(layered.cells.x) * layered.cells.y;
  std::vector<std::vector<LayerEntry>> lists(cellCount);
  for (uint32_t index : billboard.leaves) {
    LayerEntry entry = leafSprite(tree.leaves[index], billboard, params.sprite);
    entry.leaf = index;
    entry.image = orientedImageIndex(tree.leaves[index], billboard, params.bins);
    {
      const Leaf& leaf = tree.leaves[index];
      const glm::vec2 along(glm::dot(leaf.axisV, billboard.axisU),
                            glm::dot(leaf.axisV, billboard.axisV));
      const glm::vec2 inPlane(glm::dot(leaf.normal, billboard.axisU),
                              glm::dot(leaf.normal, billboard.axisV));
      entry.roll = glm::dot(inPlane, glm::vec2(-along.y, along.x)) >= 0.0f ? 1 : -1;
    }
    if (cornerOcclusion) {
      const Leaf& leaf = tree.leaves[index];
      std::vector<glm::vec2> points;
      std::vector<float> values;
      for (int c = 0; c < 4; ++c) {
        points.push_back(billboard.toPlane(leaf.corner(c)));
        values.push_back((*cornerOcclusion)[index][c]);
      }
      entry.ambient =
          glm::clamp(fitCornerValues(points, values, entry.position, entry.size), 0.0f, 1.0f);
    }
    // Cells the sprite square overlaps with positive area.
    const glm::vec2 lo =
        (entry.position - 0.5f * entry.size + billboard.halfExtents) / layered.cellSize;
    const glm::vec2 hi =
        (entry.position + 0.5f * entry.size + billboard.halfExtents) / layered.cellSize;
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y)));
    const int x1 = std::min(layered.cells.x - 1, static_cast<int>(std::ceil(hi.x)) - 1);
    const int y1 = std::min(layered.cells.y - 1, static_cast<int>(std::ceil(hi.y)) - 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) lists[size_t(y) * layered.cells.x + x].push_back(entry);
    }
  }
  layered.listStart.assign(cellCount, 0);
  layered.listLength.assign(cellCount, 0);
  for (size_t cell = 0; cell < cellCount; ++cell) {
    auto& list = lists[cell];
    // Front to back; ties by leaf index, so the order is deterministic.
    std::stable_sort(list.begin(), list.end(), [](const LayerEntry& a, const LayerEntry& b) {
      return a.depth > b.depth || (a.depth == b.depth && a.leaf < b.leaf);
    });
    if (params.maxLayers > 0 && list.size() > size_t(params.maxLayers)) {
      layered.droppedEntries += static_cast<uint32_t>(list.size() - params.maxLayers);
      list.resize(params.maxLayers);
    }
    layered.listStart[cell] = static_cast<uint32_t>(layered.entries.size());
    layered.listLength[cell] = static_cast<uint32_t>(list.size());
    layered.entries.insert(layered.entries.end(), list.begin(), list.end());
  }
  return layered;
}

std::optional<LayerHit> walkLayers(const LayeredBillboard& layered, const Billboard& billboard,
                                   const std::vector<ImageRgba8>& images,
                                   const OrientationBins& bins, glm::vec2 point, bool fromFront,
                                   int budget) {
  const glm::vec2 grid = (point + billboard.halfExtents) / layered.cellSize;
  const int cx = std::clamp(static_cast<int>(std::floor(grid.x)), 0, layered.cells.x - 1);
  const int cy = std::clamp(static_cast<int>(std::floor(grid.y)), 0, layered.cells.y - 1);
  const size_t cell = size_t(cy) * layered.cells.x + cx;
  const uint32_t length = layered.listLength[cell];
  const uint32_t count = budget < 0 ? length : std::min<uint32_t>(length, uint32_t(budget));
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t k = layered.listStart[cell] + (fromFront ? i : length - 1 - i);
    const LayerEntry& entry = layered.entries[k];
    const glm::vec2 local = (point - entry.position) / entry.size + 0.5f;
    if (local.x < 0.0f || local.y < 0.0f || local.x >= 1.0f || local.y >= 1.0f) continue;
    const ImageRgba8& image = images[fromFront ? entry.image : otherSideImage(entry.image, bins)];
    const int x = std::min(image.width - 1, static_cast<int>(local.x * image.width));
    const int y = std::min(image.height - 1, static_cast<int>(local.y * image.height));
    const uint8_t* texel = image.at(x, y);
    if (texel[3] < 128) continue;
    return LayerHit{k, glm::vec4(texel[0], texel[1], texel[2], texel[3]) / 255.0f};
  }
  return std::nullopt;
}

}  // namespace canopy
