#include "methods/multilayer_indirect/layered_billboard.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "methods/common/ambient_occlusion.h"
#include "methods/common/leaf_capture.h"

namespace canopy {

std::optional<glm::vec2> LeafRecord::locate(glm::vec2 p, glm::vec2 slope) const {
  // The ray through p meets leaf point (s, t), at height z = heightAt(s, t), where the plane
  // point it projects from satisfies c + s·a + t·b = p + z·slope; solved for (s, t).
  const glm::vec2 a = glm::vec2(axisU) - axisU.z * slope;
  const glm::vec2 b = glm::vec2(axisV) - axisV.z * slope;
  const float det = a.x * b.y - a.y * b.x;
  if (std::abs(det) <= 1e-6f * glm::length(a) * glm::length(b) || det == 0.0f) return std::nullopt;
  const glm::vec2 q = p - center + height * slope;
  return glm::vec2((q.x * b.y - q.y * b.x) / det, (a.x * q.y - a.y * q.x) / det);
}

bool LeafRecord::frontFaces(const glm::vec3& towardsViewer) const {
  return glm::dot(glm::cross(axisU, axisV), towardsViewer) > 0.0f;
}

float LeafRecord::maxCornerHeight() const {
  return std::abs(height) + std::abs(axisU.z) + std::abs(axisV.z);
}

void LeafRecord::footprint(float maxSlope, glm::vec2& lo, glm::vec2& hi) const {
  lo = glm::vec2(std::numeric_limits<float>::max());
  hi = glm::vec2(std::numeric_limits<float>::lowest());
  for (int corner = 0; corner < 4; ++corner) {
    const glm::vec2 st((corner == 1 || corner == 2) ? 1.0f : -1.0f, corner >= 2 ? 1.0f : -1.0f);
    const glm::vec2 p = center + st.x * glm::vec2(axisU) + st.y * glm::vec2(axisV);
    // Seen along a ray of slope w, a point at height z shows at plane point p − z·w.
    const float reach = std::abs(heightAt(st)) * maxSlope;
    lo = glm::min(lo, p - reach);
    hi = glm::max(hi, p + reach);
  }
}

LeafRecord makeLeafRecord(const Leaf& leaf, const Billboard& billboard, uint32_t image) {
  const auto inFrame = [&](const glm::vec3& v) {
    return glm::vec3(glm::dot(v, billboard.axisU), glm::dot(v, billboard.axisV),
                     glm::dot(v, billboard.normal));
  };
  LeafRecord record;
  record.center = billboard.toPlane(leaf.center);
  record.height = glm::dot(leaf.center - billboard.center, billboard.normal);
  record.axisU = inFrame(leaf.axisU * leaf.halfExtents.x);
  record.axisV = inFrame(leaf.axisV * leaf.halfExtents.y);
  record.image = image;
  return record;
}

LayeredBillboard buildLayeredBillboard(const Tree& tree, const Billboard& billboard,
                                       const std::vector<uint32_t>& imageOfLeaf,
                                       const LayeringParams& params,
                                       const std::vector<glm::vec4>* cornerOcclusion) {
  LayeredBillboard layered;
  layered.halfExtents = billboard.halfExtents;
  std::vector<glm::vec2> lows, highs;
  for (uint32_t index : billboard.leaves) {
    LeafRecord record = makeLeafRecord(tree.leaves[index], billboard, imageOfLeaf[index]);
    record.leaf = index;
    if (cornerOcclusion) record.ambient = (*cornerOcclusion)[index];
    glm::vec2 lo, hi;
    record.footprint(params.maxSlope, lo, hi);
    // The billboard's rectangle already holds every projected corner; parallax grows it.
    if (params.maxSlope > 0.0f)
      layered.halfExtents = glm::max(layered.halfExtents, glm::max(-lo, hi));
    lows.push_back(lo);
    highs.push_back(hi);
    layered.records.push_back(record);
  }
  const float target = params.cellSize;
  layered.cells = {
      std::max(1, static_cast<int>(std::lround(2.0f * layered.halfExtents.x / target))),
      std::max(1, static_cast<int>(std::lround(2.0f * layered.halfExtents.y / target)))};
  layered.cellSize = 2.0f * layered.halfExtents / glm::vec2(layered.cells);
  const size_t cellCount = size_t(layered.cells.x) * layered.cells.y;
  std::vector<std::vector<uint32_t>> lists(cellCount);
  for (uint32_t r = 0; r < layered.records.size(); ++r) {
    // Cells the footprint overlaps with positive area.
    const glm::vec2 lo = (lows[r] + layered.halfExtents) / layered.cellSize;
    const glm::vec2 hi = (highs[r] + layered.halfExtents) / layered.cellSize;
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y)));
    const int x1 = std::min(layered.cells.x - 1, static_cast<int>(std::ceil(hi.x)) - 1);
    const int y1 = std::min(layered.cells.y - 1, static_cast<int>(std::ceil(hi.y)) - 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) lists[size_t(y) * layered.cells.x + x].push_back(r);
    }
  }
  layered.listStart.assign(cellCount, 0);
  layered.listLength.assign(cellCount, 0);
  const auto& records = layered.records;
  for (size_t cell = 0; cell < cellCount; ++cell) {
    auto& list = lists[cell];
    // Front to back; ties by leaf index, so the order is deterministic.
    std::sort(list.begin(), list.end(), [&](uint32_t a, uint32_t b) {
      return records[a].height > records[b].height ||
             (records[a].height == records[b].height && records[a].leaf < records[b].leaf);
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

std::optional<LayerHit> walkLayers(const LayeredBillboard& layered,
                                   const std::vector<ImageRgba8>& leafLayers, glm::vec2 point,
                                   bool fromFront, int budget) {
  const glm::vec2 grid = (point + layered.halfExtents) / layered.cellSize;
  const int cx = std::clamp(static_cast<int>(std::floor(grid.x)), 0, layered.cells.x - 1);
  const int cy = std::clamp(static_cast<int>(std::floor(grid.y)), 0, layered.cells.y - 1);
  const size_t cell = size_t(cy) * layered.cells.x + cx;
  const uint32_t length = layered.listLength[cell];
  const uint32_t count = budget < 0 ? length : std::min<uint32_t>(length, uint32_t(budget));
  const glm::vec3 towardsViewer(0.0f, 0.0f, fromFront ? 1.0f : -1.0f);
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t r = layered.entries[layered.listStart[cell] + (fromFront ? i : length - 1 - i)];
    const LeafRecord& record = layered.records[r];
    const auto st = record.locate(point, glm::vec2(0.0f));
    if (!st || std::abs(st->x) > 1.0f || std::abs(st->y) > 1.0f) continue;
    const ImageRgba8& image =
        leafLayers[2 * record.image + (record.frontFaces(towardsViewer) ? 0 : 1)];
    const glm::vec2 uv = (*st + 1.0f) * 0.5f;
    const int x = std::min(image.width - 1, static_cast<int>(uv.x * image.width));
    const int y = std::min(image.height - 1, static_cast<int>(uv.y * image.height));
    const uint8_t* texel = image.at(x, y);
    if (texel[3] < 128) continue;
    return LayerHit{r, *st, glm::vec4(texel[0], texel[1], texel[2], texel[3]) / 255.0f};
  }
  return std::nullopt;
}

ImageRgba8 captureLayered(const LayeredBillboard& layered,
                          const std::vector<ImageRgba8>& leafLayers, int texelsPerCell,
                          bool fromFront, ImageRgba8* occlusion, const LayeredWood* wood) {
  constexpr int kSamples = 4;
  const glm::ivec2 size = layered.cells * texelsPerCell;
  const int sw = size.x * kSamples, sh = size.y * kSamples;
  // Every sample first: what the walk hits and at which height, so the wood can hide it.
  std::vector<float> nearness(size_t(sw) * sh, -std::numeric_limits<float>::infinity());
  std::vector<glm::vec3> color(nearness.size(), glm::vec3(0.0f));
  std::vector<float> ambient(nearness.size(), 1.0f);
  for (int y = 0; y < sh; ++y) {
    for (int x = 0; x < sw; ++x) {
      const glm::vec2 unit((x + 0.5f) / sw, (y + 0.5f) / sh);
      const glm::vec2 point = (unit * 2.0f - 1.0f) * layered.halfExtents;
      const auto hit = walkLayers(layered, leafLayers, point, fromFront);
      if (!hit) continue;
      const LeafRecord& record = layered.records[hit->record];
      const size_t s = size_t(y) * sw + x;
      nearness[s] = fromFront ? record.heightAt(hit->st) : -record.heightAt(hit->st);
      color[s] = glm::vec3(srgbToLinear(hit->color.r), srgbToLinear(hit->color.g),
                           srgbToLinear(hit->color.b));
      ambient[s] = interpolateCorners(record.ambient, (hit->st + 1.0f) * 0.5f);
    }
  }
  if (wood) {
    std::vector<bool> isWood(nearness.size(), false);
    OrthographicSamples samples{sw, sh, nearness, color, &isWood};
    rasterizeWoodOrthographic(wood->tree, wood->colors, wood->triangles, wood->billboard,
                              !fromFront, samples);
    for (size_t s = 0; s < isWood.size(); ++s)
      if (isWood[s]) ambient[s] = 1.0f;
  }
  ImageRgba8 image(size.x, size.y);
  if (occlusion) *occlusion = ImageRgba8(size.x, size.y);
  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      glm::vec3 sum(0.0f);
      float ambientSum = 0.0f;
      int covered = 0;
      for (int sy = 0; sy < kSamples; ++sy) {
        for (int sx = 0; sx < kSamples; ++sx) {
          const size_t s = size_t(y * kSamples + sy) * sw + (x * kSamples + sx);
          if (nearness[s] == -std::numeric_limits<float>::infinity()) continue;
          sum += color[s];
          ambientSum += ambient[s];
          ++covered;
        }
      }
      writeCoverageTexel(image.at(x, y), sum, covered, kSamples * kSamples);
      if (occlusion) {
        uint8_t* out = occlusion->at(x, y);
        const float value = covered ? ambientSum / float(covered) : 1.0f;
        out[0] = out[1] = out[2] = uint8_t(std::lround(255.0f * value));
        out[3] = image.at(x, y)[3];
      }
    }
  }
  return image;
}

}  // namespace canopy
