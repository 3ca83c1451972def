#include "methods/volumetric_opacity/view_textures.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>
#include <opencv2/core.hpp>
#include <opencv2/photo.hpp>

namespace canopy {

glm::vec2 billboardHalfExtents(float cellSize, const glm::vec3& right, const glm::vec3& up) {
  const glm::vec3 r = glm::abs(right), u = glm::abs(up);
  return 0.5f * cellSize * glm::vec2(r.x + r.y + r.z, u.x + u.y + u.z);
}

std::vector<int> selectTexels(const std::vector<uint16_t>& ages,
                              const std::vector<float>& importance, float tc) {
  const int count = int(ages.size());
  const int keep = std::clamp(int(std::floor((1.0f - tc) * float(count))), 0, count);
  std::vector<int> order(static_cast<size_t>(count));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (ages[a] != ages[b]) return ages[a] > ages[b];  // older first: spreads the choice (§6)
    return importance[a] > importance[b];
  });
  order.resize(size_t(keep));
  return order;
}

namespace {

struct Tile {
  int32_t cell;
  std::vector<uint8_t> alpha, rgb;
};

// One view's textures, in front-to-back cell order.
std::vector<Tile> texturesOfView(const OpacityGrid& grid, const OpacityView& view,
                                 const TextureSettings& settings) {
  const PixelCamera& cam = view.camera;
  const int width = cam.width(), height = cam.height(), m = settings.texels;
  const ImageRgbaF& image = *view.image;
  // The copy C_i of the pure-foreground colour (Eq. 3: premultiplied / α), 8-bit sRGB for
  // OpenCV's inpainting.
  cv::Mat copy(height, width, CV_8UC3);
  std::vector<float> tCurr(size_t(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float* p = image.at(x, y);
      const float a = p[3];
      cv::Vec3b& out = copy.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c)
        out[c] = a > 1e-4f ? encodeSrgb8(std::clamp(p[c] / a, 0.0f, 1.0f)) : 0;
      tCurr[size_t(y) * width + x] = 1.0f - a;
    }
  }
  const glm::vec2 half = billboardHalfExtents(grid.cellSize, cam.right(), cam.up());
  struct Region {
    int32_t cell;
    glm::vec2 lo, size;  // billboard rectangle in pixel coordinates
    int x0, y0, x1, y1;  // pixels whose centres it covers, [x0, x1) × [y0, y1)
  };
  std::vector<Region> regions;
  for (size_t c = 0; c < grid.cells.size(); ++c) {
    if (grid.transparency[c] >= 1.0f) continue;
    const glm::vec3 center = grid.cellCenter(c);
    const float z = cam.depth(center);
    if (z <= 1e-4f) continue;
    const glm::vec2 p = cam.project(center), h = half * cam.focalPixels() / z;
    Region r{int32_t(c), p - h, 2.0f * h, 0, 0, 0, 0};
    r.x0 = std::max(0, int(std::ceil(p.x - h.x - 0.5f)));
    r.y0 = std::max(0, int(std::ceil(p.y - h.y - 0.5f)));
    r.x1 = std::min(width, int(std::floor(p.x + h.x - 0.5f)) + 1);
    r.y1 = std::min(height, int(std::floor(p.y + h.y - 0.5f)) + 1);
    regions.push_back(r);
  }
  // Front to back (§6), ties by cell index.
  std::vector<float> depth(regions.size());
  for (size_t i = 0; i < regions.size(); ++i)
    depth[i] = cam.depth(grid.cellCenter(regions[i].cell));
  std::vector<size_t> order(regions.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return depth[a] < depth[b]; });
  // N_curr: the billboards covering each pixel (the paper counts them with the stencil buffer).
  std::vector<uint16_t> nCurr(size_t(width) * height, 0), age(size_t(width) * height, 0);
  for (const Region& r : regions)
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x) ++nCurr[size_t(y) * width + x];

  std::vector<Tile> tiles;
  const int texelCount = m * m;
  std::vector<uint16_t> texelAge(static_cast<size_t>(texelCount));
  std::vector<float> importance(static_cast<size_t>(texelCount));
  std::vector<int> texelPixel(static_cast<size_t>(texelCount));
  cv::Mat removed(height, width, CV_8U, cv::Scalar(0));
  for (size_t k : order) {
    const Region& r = regions[k];
    const float tc = grid.transparency[r.cell];
    // Resample the billboard's texels from the image (nearest pixel).
    for (int b = 0; b < m; ++b) {
      for (int a = 0; a < m; ++a) {
        const int x = std::clamp(int(std::floor(r.lo.x + (float(a) + 0.5f) / float(m) * r.size.x)),
                                 0, width - 1);
        const int y = std::clamp(int(std::floor(r.lo.y + (float(b) + 0.5f) / float(m) * r.size.y)),
                                 0, height - 1);
        const size_t pixel = size_t(y) * width + x;
        const int t = b * m + a;
        texelPixel[t] = int(pixel);
        texelAge[t] = age[pixel];
        // Eq. 14: texels whose remaining transparency matches this cell's share score high.
        const float expected = std::pow(tc, float(std::max<uint16_t>(nCurr[pixel], 1)));
        importance[t] = 1.0f / (std::abs(tCurr[pixel] - expected) + 1e-6f);
      }
    }
    const std::vector<int> selected = selectTexels(texelAge, importance, tc);
    Tile tile{r.cell, std::vector<uint8_t>(size_t(texelCount), 0),
              std::vector<uint8_t>(size_t(texelCount) * 3, 0)};
    bool any = false;
    for (int t : selected) {
      const int pixel = texelPixel[t];
      const int x = pixel % width, y = pixel / width;
      const float alpha = image.at(x, y)[3];
      tile.alpha[t] = uint8_t(std::lround(std::clamp(alpha, 0.0f, 1.0f) * 255.0f));
      const cv::Vec3b& colour = copy.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) tile.rgb[size_t(t) * 3 + c] = colour[c];
      any = any || tile.alpha[t] > 0;
    }
    // Update the pixels under selected texels (t_curr /= t_c, removed from the copy) once each.
    int rx0 = width, ry0 = height, rx1 = -1, ry1 = -1;
    for (int t : selected) {
      const int pixel = texelPixel[t];
      const int x = pixel % width, y = pixel / width;
      uint8_t& mark = removed.at<uint8_t>(y, x);
      if (mark) continue;
      mark = 255;
      tCurr[pixel] = std::min(1.0f, tCurr[pixel] / std::max(tc, 1e-3f));
      rx0 = std::min(rx0, x), ry0 = std::min(ry0, y), rx1 = std::max(rx1, x),
      ry1 = std::max(ry1, y);
    }
    for (int y = r.y0; y < r.y1; ++y) {
      for (int x = r.x0; x < r.x1; ++x) {
        const size_t pixel = size_t(y) * width + x;
        if (!removed.at<uint8_t>(y, x) && age[pixel] < UINT16_MAX) ++age[pixel];
        if (nCurr[pixel] > 0) --nCurr[pixel];
      }
    }
    if (rx1 >= 0) {
      // Refill the removed pixels from their neighbours (§6), in a window around them.
      const int pad = settings.inpaintRadius + 1;
      const cv::Rect roi(std::max(0, rx0 - pad), std::max(0, ry0 - pad),
                         std::min(width, rx1 + pad + 1) - std::max(0, rx0 - pad),
                         std::min(height, ry1 + pad + 1) - std::max(0, ry0 - pad));
      if (settings.inpaint) {
        cv::Mat filled;
        cv::inpaint(copy(roi), removed(roi), filled, settings.inpaintRadius, cv::INPAINT_TELEA);
        filled.copyTo(copy(roi), removed(roi));
      }
      removed(roi).setTo(0);
    }
    if (any) tiles.push_back(std::move(tile));
  }
  return tiles;
}

}  // namespace

ViewTextures generateViewTextures(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                                  const TextureSettings& settings) {
  std::vector<std::vector<Tile>> perView(views.size());
  tbb::parallel_for(size_t(0), views.size(),
                    [&](size_t v) { perView[v] = texturesOfView(grid, views[v], settings); });
  ViewTextures textures;
  textures.texels = settings.texels;
  textures.views = int(views.size());
  textures.cells = int(grid.cells.size());
  textures.tile.assign(size_t(textures.views) * textures.cells, kNoTile);
  uint32_t next = 0;
  for (size_t v = 0; v < perView.size(); ++v) {
    // Tiles stored in cell order within a view, so the layout does not depend on depth ties.
    std::sort(perView[v].begin(), perView[v].end(),
              [](const Tile& a, const Tile& b) { return a.cell < b.cell; });
    for (Tile& tile : perView[v]) {
      textures.tile[v * textures.cells + size_t(tile.cell)] = next++;
      textures.alpha.insert(textures.alpha.end(), tile.alpha.begin(), tile.alpha.end());
      textures.rgb.insert(textures.rgb.end(), tile.rgb.begin(), tile.rgb.end());
    }
  }
  return textures;
}

PackedTextures packTextures(const ViewTextures& textures) {
  PackedTextures packed;
  packed.texels = textures.texels;
  packed.tile = textures.tile;
  packed.alpha = textures.alpha;
  const size_t texelCount = size_t(textures.texels) * textures.texels;
  const size_t tiles = textures.tileCount();
  const auto maskOf = [&](size_t tile) {
    std::vector<bool> mask(texelCount);
    for (size_t t = 0; t < texelCount; ++t) mask[t] = textures.alpha[tile * texelCount + t] > 0;
    return mask;
  };
  const auto disjoint = [](const std::vector<bool>& a, const std::vector<bool>& b) {
    for (size_t t = 0; t < a.size(); ++t)
      if (a[t] && b[t]) return false;
    return true;
  };
  // Greedy, deterministic: a texture joins one of the most recent half-filled slots whose
  // alpha it does not intersect, or opens a slot.
  constexpr size_t kWindow = 64;
  struct OpenSlot {
    uint32_t slot;
    std::vector<bool> mask;
  };
  std::vector<OpenSlot> open;
  packed.slotOfTile.assign(tiles, 0);
  for (size_t tile = 0; tile < tiles; ++tile) {
    std::vector<bool> mask = maskOf(tile);
    const uint8_t* rgb = &textures.rgb[tile * texelCount * 3];
    bool placed = false;
    for (size_t k = open.size(); k-- > 0 && open.size() - k <= kWindow;) {
      if (!disjoint(open[k].mask, mask)) continue;
      const uint32_t slot = open[k].slot;
      packed.slotOfTile[tile] = slot;
      uint8_t* destination = &packed.slotRgb[slot * texelCount * 3];
      for (size_t t = 0; t < texelCount; ++t)
        if (mask[t]) std::copy_n(rgb + t * 3, 3, destination + t * 3);
      open.erase(open.begin() + std::ptrdiff_t(k));
      placed = true;
      break;
    }
    if (placed) continue;
    const auto slot = uint32_t(packed.slotRgb.size() / (texelCount * 3));
    packed.slotOfTile[tile] = slot;
    packed.slotRgb.insert(packed.slotRgb.end(), rgb, rgb + texelCount * 3);
    open.push_back({slot, std::move(mask)});
  }
  return packed;
}

}  // namespace canopy
