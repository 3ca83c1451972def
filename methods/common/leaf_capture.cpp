#include "methods/common/leaf_capture.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace canopy {

LinearMipPyramid::LinearMipPyramid(const ImageRgba8& image) {
  mLevels.resize(1);
  mLevels[0].width = image.width;
  mLevels[0].height = image.height;
  mLevels[0].texels.resize(size_t(image.width) * image.height);
  for (size_t i = 0; i < mLevels[0].texels.size(); ++i) {
    const uint8_t* p = &image.pixels[i * 4];
    mLevels[0].texels[i] = {srgbToLinear(p[0] / 255.0f), srgbToLinear(p[1] / 255.0f),
                            srgbToLinear(p[2] / 255.0f), p[3] / 255.0f};
  }
  while (mLevels.back().width > 1 || mLevels.back().height > 1) {
    const Level& fine = mLevels.back();
    Level coarse;
    coarse.width = std::max(1, fine.width / 2);
    coarse.height = std::max(1, fine.height / 2);
    coarse.texels.resize(size_t(coarse.width) * coarse.height);
    for (int y = 0; y < coarse.height; ++y) {
      for (int x = 0; x < coarse.width; ++x) {
        glm::vec4 sum(0.0f);
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const int fx = std::min(fine.width - 1, x * 2 + dx),
                      fy = std::min(fine.height - 1, y * 2 + dy);
            const glm::vec4 t = fine.texels[size_t(fy) * fine.width + fx];
            sum += glm::vec4(glm::vec3(t) * t.a, t.a);
          }
        }
        coarse.texels[size_t(y) * coarse.width + x] =
            sum.a > 0.0f ? glm::vec4(glm::vec3(sum) / sum.a, sum.a * 0.25f) : glm::vec4(0.0f);
      }
    }
    mLevels.push_back(std::move(coarse));
  }
}

glm::vec4 LinearMipPyramid::sample(glm::vec2 uv, float footprint) const {
  const int level =
      std::clamp(static_cast<int>(std::floor(std::log2(std::max(footprint, 1.0f)) + 0.5f)), 0,
                 static_cast<int>(mLevels.size()) - 1);
  const Level& l = mLevels[level];
  const float x = uv.x * l.width - 0.5f, y = uv.y * l.height - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  auto at = [&](int px, int py) {
    px = std::clamp(px, 0, l.width - 1);
    py = std::clamp(py, 0, l.height - 1);
    return l.texels[size_t(py) * l.width + px];
  };
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), fx),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx), fy);
}

LeafImageSampler::LeafImageSampler(const Tree& tree) {
  for (const LeafTexture& texture : tree.leafTextures) {
    mPyramids.emplace_back(texture.front);
    mPyramids.emplace_back(texture.back);
  }
}

glm::ivec2 LeafImageSampler::size(uint32_t texture) const {
  return mPyramids[texture * 2].size();
}

glm::vec4 LeafImageSampler::sample(uint32_t texture, bool back, glm::vec2 uv,
                                   float footprint) const {
  return mPyramids[texture * 2 + (back ? 1 : 0)].sample(uv, footprint);
}

WoodColorSampler::WoodColorSampler(const Tree& tree) : mWood(tree.wood) {
  for (const ImageRgba8& image : tree.woodTextures) mPyramids.emplace_back(image);
  for (const WoodMaterial& material : tree.woodMaterials) {
    mBaseColors.emplace_back(srgbToLinear(material.baseColor.r), srgbToLinear(material.baseColor.g),
                             srgbToLinear(material.baseColor.b));
    mTextures.push_back(material.texture);
  }
}

glm::vec3 WoodColorSampler::sample(uint32_t triangle, const glm::vec3& weights,
                                   float sampleSize) const {
  const uint16_t material = mWood.materialIds[triangle];
  const glm::vec3 base = mBaseColors[material];
  if (mTextures[material] < 0) return base;
  const LinearMipPyramid& texture = mPyramids[size_t(mTextures[material])];
  glm::vec2 uv(0.0f);
  glm::vec3 corners[3];
  glm::vec2 uvs[3];
  for (int k = 0; k < 3; ++k) {
    const uint32_t vertex = mWood.indices[triangle * 3 + k];
    corners[k] = mWood.positions[vertex];
    uvs[k] = mWood.uvs[vertex];
    uv += weights[k] * uvs[k];
  }
  // Texels per world unit over this triangle: the square root of its texel area over its area.
  const glm::vec2 size(texture.size());
  const glm::vec2 du = (uvs[1] - uvs[0]) * size, dv = (uvs[2] - uvs[0]) * size;
  const float texelArea = std::abs(du.x * dv.y - du.y * dv.x);
  const float area = glm::length(glm::cross(corners[1] - corners[0], corners[2] - corners[0]));
  const float texelsPerUnit = area > 0.0f ? std::sqrt(texelArea / area) : 0.0f;
  return base * glm::vec3(texture.sample(uv, sampleSize * texelsPerUnit));
}

void writeCoverageTexel(uint8_t* out, const glm::vec3& linearSum, int covered, int samples) {
  if (covered > 0) {
    for (int c = 0; c < 3; ++c) out[c] = encodeSrgb8(linearSum[c] / float(covered));
  }
  out[3] = static_cast<uint8_t>(std::lround(255.0f * float(covered) / float(samples)));
}

ImageRgba8 renderCoverageImage(int size, int supersample,
                               const std::function<glm::vec4(glm::vec2 unit)>& sample) {
  ImageRgba8 image(size, size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      glm::vec3 sum(0.0f);
      int covered = 0;
      for (int sy = 0; sy < supersample; ++sy) {
        for (int sx = 0; sx < supersample; ++sx) {
          const glm::vec4 texel = sample(glm::vec2((x + (sx + 0.5f) / supersample) / size,
                                                   (y + (sy + 0.5f) / supersample) / size));
          if (texel.a < 0.5f) continue;
          sum += glm::vec3(texel);
          ++covered;
        }
      }
      writeCoverageTexel(image.at(x, y), sum, covered, supersample * supersample);
    }
  }
  dilateTransparentColors(image, 4);
  return image;
}

void rasterizeWoodOrthographic(const Tree& tree, const WoodColorSampler& wood,
                               const std::vector<uint32_t>& triangles, const Billboard& billboard,
                               bool fromBack, OrthographicSamples& samples) {
  const int sw = samples.width, sh = samples.height;
  const float stepU = 2.0f * billboard.halfExtents.x / float(sw);
  const float stepV = 2.0f * billboard.halfExtents.y / float(sh);
  for (uint32_t triangle : triangles) {
    // Corners on the plane (x, y in samples) and their heights along the normal.
    glm::vec2 at[3];
    float height[3];
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 p = tree.wood.positions[tree.wood.indices[triangle * 3 + k]];
      const glm::vec2 q = billboard.toPlane(p) + billboard.halfExtents;
      at[k] = {q.x / stepU, q.y / stepV};
      height[k] = glm::dot(p - billboard.center, billboard.normal);
    }
    const float area =
        (at[1].x - at[0].x) * (at[2].y - at[0].y) - (at[2].x - at[0].x) * (at[1].y - at[0].y);
    if (std::abs(area) < 1e-12f) continue;  // edge-on
    const glm::vec2 lo = glm::min(at[0], glm::min(at[1], at[2]));
    const glm::vec2 hi = glm::max(at[0], glm::max(at[1], at[2]));
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x)));
    const int x1 = std::min(sw - 1, static_cast<int>(std::floor(hi.x)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y)));
    const int y1 = std::min(sh - 1, static_cast<int>(std::floor(hi.y)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const glm::vec2 p(x + 0.5f, y + 0.5f);
        // Barycentric weights of the sample centre; outside when any is negative.
        const auto edge = [&](int a, int b) {
          return ((at[b].x - at[a].x) * (p.y - at[a].y) - (p.x - at[a].x) * (at[b].y - at[a].y)) /
                 area;
        };
        const glm::vec3 weights(edge(1, 2), edge(2, 0), edge(0, 1));
        if (weights.x < 0.0f || weights.y < 0.0f || weights.z < 0.0f) continue;
        const float t = weights.x * height[0] + weights.y * height[1] + weights.z * height[2];
        const float nearness = fromBack ? -t : t;
        const size_t s = size_t(y) * sw + x;
        if (nearness <= samples.nearness[s]) continue;
        samples.nearness[s] = nearness;
        samples.color[s] = wood.sample(triangle, weights, std::max(stepU, stepV));
        if (samples.wood) (*samples.wood)[s] = true;
      }
    }
  }
}

ImageRgba8 captureLeavesOrthographic(const Tree& tree, const LeafImageSampler& sampler,
                                     const std::vector<uint32_t>& leaves,
                                     const Billboard& billboard, int width, int height,
                                     int supersample, bool fromBack, const WoodColorSampler* wood,
                                     const std::vector<uint32_t>& woodTriangles) {
  const int sw = width * supersample, sh = height * supersample;
  std::vector<float> depth(size_t(sw) * sh, -std::numeric_limits<float>::infinity());
  std::vector<glm::vec3> color(size_t(sw) * sh, glm::vec3(0.0f));
  const glm::vec2 extent = billboard.halfExtents * 2.0f;
  const float stepU = extent.x / float(sw), stepV = extent.y / float(sh);
  for (uint32_t index : leaves) {
    const Leaf& leaf = tree.leaves[index];
    const float facing = glm::dot(leaf.normal, billboard.normal);
    if (std::abs(facing) < 1e-4f) continue;  // edge-on: no projected area
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
    for (int c = 0; c < 4; ++c) {
      const glm::vec2 p = billboard.toPlane(leaf.corner(c));
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const int x0 =
        std::max(0, static_cast<int>(std::floor((lo.x + billboard.halfExtents.x) / stepU)));
    const int x1 =
        std::min(sw - 1, static_cast<int>(std::floor((hi.x + billboard.halfExtents.x) / stepU)));
    const int y0 =
        std::max(0, static_cast<int>(std::floor((lo.y + billboard.halfExtents.y) / stepV)));
    const int y1 =
        std::min(sh - 1, static_cast<int>(std::floor((hi.y + billboard.halfExtents.y) / stepV)));
    const glm::ivec2 texSize = sampler.size(leaf.texture);
    // Leaf texels under one sample, foreshortening included.
    const float footprint =
        std::max(stepU, stepV) / std::abs(facing) *
        std::max(texSize.x * std::abs(leaf.uvMax.x - leaf.uvMin.x) / (2.0f * leaf.halfExtents.x),
                 texSize.y * std::abs(leaf.uvMax.y - leaf.uvMin.y) / (2.0f * leaf.halfExtents.y));
    // The camera looks along −normal (front capture) or +normal (back capture).
    const bool back = fromBack ? facing > 0.0f : facing < 0.0f;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const glm::vec3 p = billboard.center +
                            billboard.axisU * (-billboard.halfExtents.x + (x + 0.5f) * stepU) +
                            billboard.axisV * (-billboard.halfExtents.y + (y + 0.5f) * stepV);
        const float t = glm::dot(leaf.normal, leaf.center - p) / facing;
        const float nearness = fromBack ? -t : t;  // larger: nearer the camera
        const size_t s = size_t(y) * sw + x;
        if (nearness <= depth[s]) continue;
        const glm::vec3 onLeaf = p + billboard.normal * t - leaf.center;
        const float a = glm::dot(onLeaf, leaf.axisU) / leaf.halfExtents.x;
        const float b = glm::dot(onLeaf, leaf.axisV) / leaf.halfExtents.y;
        if (std::abs(a) > 1.0f || std::abs(b) > 1.0f) continue;
        const glm::vec2 uv =
            leaf.uvMin + (glm::vec2(a, b) + 1.0f) * 0.5f * (leaf.uvMax - leaf.uvMin);
        const glm::vec4 texel = sampler.sample(leaf.texture, back, uv, footprint);
        if (texel.a < 0.5f) continue;
        depth[s] = nearness;
        color[s] = glm::vec3(texel);
      }
    }
  }
  if (wood != nullptr) {
    OrthographicSamples samples{sw, sh, depth, color};
    rasterizeWoodOrthographic(tree, *wood, woodTriangles, billboard, fromBack, samples);
  }
  ImageRgba8 image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      glm::vec3 sum(0.0f);
      int covered = 0;
      for (int sy = 0; sy < supersample; ++sy) {
        for (int sx = 0; sx < supersample; ++sx) {
          const size_t s = size_t(y * supersample + sy) * sw + (x * supersample + sx);
          if (depth[s] == -std::numeric_limits<float>::infinity()) continue;
          sum += color[s];
          ++covered;
        }
      }
      writeCoverageTexel(image.at(x, y), sum, covered, supersample * supersample);
    }
  }
  return image;
}

AtlasLayout packAtlas(const std::vector<glm::ivec2>& sizes, int padding, int alignment) {
  // A rectangle's slot is aligned to the largest power of two up to `alignment` that its longer
  // side reaches, its padding at most half that: beyond those mip levels the whole rectangle is
  // under one texel, i.e. under a pixel on screen. Small rectangles (the split clouds' hundreds
  // of tiny billboards) then cost little more than their texels.
  const auto slotOf = [&](const glm::ivec2& size) {
    int align = 1;
    while (align * 2 <= alignment && align * 2 <= std::max(size.x, size.y)) align *= 2;
    const int pad = std::min(padding, std::max(1, align / 2));
    const auto up = [&](int v) { return (v + align - 1) / align * align; };
    struct Slot {
      glm::ivec2 size;
      int padding, align;
    };
    return Slot{glm::ivec2(up(size.x + 2 * pad), up(size.y + 2 * pad)), pad, align};
  };
  std::vector<size_t> order(sizes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return slotOf(sizes[a]).size.y > slotOf(sizes[b]).size.y;
  });
  double area = 0.0;
  int widest = 1;
  for (const glm::ivec2& s : sizes) {
    const glm::ivec2 slot = slotOf(s).size;
    area += double(slot.x) * slot.y;
    widest = std::max(widest, slot.x);
  }
  AtlasLayout layout;
  layout.width = 1;
  while (layout.width < widest || double(layout.width) * layout.width < area) layout.width *= 2;
  layout.origins.resize(sizes.size());
  int x = 0, y = 0, shelfHeight = 0;
  for (size_t i : order) {
    const auto [slot, pad, align] = slotOf(sizes[i]);
    x = (x + align - 1) / align * align;
    if (x + slot.x > layout.width) {
      x = 0;
      // Shelves start at multiples of the largest alignment, so every slot's y is aligned too.
      y = (y + shelfHeight + alignment - 1) / alignment * alignment;
      shelfHeight = 0;
    }
    layout.origins[i] = {x + pad, y + pad};
    x += slot.x;
    shelfHeight = std::max(shelfHeight, slot.y);
  }
  layout.height = std::max(alignment, y + shelfHeight);
  return layout;
}

glm::vec2 ImageAtlas::cornerUv(size_t index, int corner) const {
  static constexpr int kU[4] = {0, 1, 1, 0}, kV[4] = {0, 0, 1, 1};
  const glm::vec2 texel = glm::vec2(layout.origins[index]) +
                          glm::vec2(kU[corner] * sizes[index].x, kV[corner] * sizes[index].y);
  return texel / glm::vec2(layout.width, layout.height);
}

ImageAtlas composeAtlas(const std::vector<ImageRgba8>& images, int padding, int alignment) {
  ImageAtlas atlas;
  for (const ImageRgba8& image : images) atlas.sizes.emplace_back(image.width, image.height);
  atlas.layout = packAtlas(atlas.sizes, padding, alignment);
  atlas.image = ImageRgba8(atlas.layout.width, atlas.layout.height);
  for (size_t i = 0; i < images.size(); ++i) {
    for (int y = 0; y < images[i].height; ++y) {
      std::copy_n(images[i].at(0, y), size_t(images[i].width) * 4,
                  atlas.image.at(atlas.layout.origins[i].x, atlas.layout.origins[i].y + y));
    }
  }
  dilateTransparentColors(atlas.image, alignment);
  return atlas;
}

TwoSidedAtlas captureTwoSidedAtlas(const Tree& tree, const LeafImageSampler& sampler,
                                   const std::vector<const Billboard*>& billboards,
                                   const std::vector<glm::ivec2>& sizes, int supersample,
                                   bool backToo, int padding, int alignment,
                                   const WoodColorSampler* wood,
                                   const std::vector<std::vector<uint32_t>>* woodPerBillboard) {
  const size_t count = billboards.size();
  std::vector<ImageRgba8> images(count * (backToo ? 2 : 1));
  static const std::vector<uint32_t> kNoWood;
  tbb::parallel_for(size_t(0), images.size(), [&](size_t k) {
    const size_t i = k % count;
    images[k] = captureLeavesOrthographic(tree, sampler, billboards[i]->leaves, *billboards[i],
                                          sizes[i].x, sizes[i].y, supersample, k >= count, wood,
                                          woodPerBillboard ? (*woodPerBillboard)[i] : kNoWood);
  });
  TwoSidedAtlas atlas;
  atlas.front = composeAtlas({images.begin(), images.begin() + long(count)}, padding, alignment);
  if (backToo)
    atlas.back =
        composeAtlas({images.begin() + long(count), images.end()}, padding, alignment).image;
  return atlas;
}

void dilateTransparentColors(ImageRgba8& image, int passes) {
  std::vector<uint8_t> filled(size_t(image.width) * image.height);
  for (size_t i = 0; i < filled.size(); ++i) filled[i] = image.pixels[i * 4 + 3] > 0;
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<uint8_t> next = filled;
    ImageRgba8 source = image;
    bool changed = false;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        const size_t i = size_t(y) * image.width + x;
        if (filled[i]) continue;
        int sum[3] = {0, 0, 0}, count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= image.width || ny >= image.height) continue;
            const size_t j = size_t(ny) * image.width + nx;
            if (!filled[j]) continue;
            for (int c = 0; c < 3; ++c) sum[c] += source.pixels[j * 4 + c];
            ++count;
          }
        }
        if (count == 0) continue;
        for (int c = 0; c < 3; ++c) image.pixels[i * 4 + c] = static_cast<uint8_t>(sum[c] / count);
        next[i] = 1;
        changed = true;
      }
    }
    filled.swap(next);
    if (!changed) break;
  }
}

}  // namespace canopy
