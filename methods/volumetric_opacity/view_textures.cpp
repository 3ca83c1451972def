#include "methods/volumetric_opacity/view_textures.h"

#include <tbb/parallel_for.h>

#include <algorithm>
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

// A finished texture of one view: M² texels of sRGB colour and linear alpha.
struct Tile {
  int32_t cell;
  std::vector<uint8_t> rgba;
  bool hidden = false;  // every texel's contribution below the hidden cutoff (kPartition)
};

// A cell's billboard in one view's pixel coordinates.
struct Region {
  int32_t cell;
  glm::vec2 lo, size;  // billboard rectangle in pixel coordinates
  int x0, y0, x1, y1;  // pixels whose centres it covers, [x0, x1) × [y0, y1)
  float depth;         // of the cell's centre
  // Pixel under texel (a, b) (rows from the billboard's top): the one holding its centre.
  glm::ivec2 pixelOf(int a, int b, int m, int width, int height) const {
    return {
        std::clamp(int(std::floor(lo.x + (float(a) + 0.5f) / float(m) * size.x)), 0, width - 1),
        std::clamp(int(std::floor(lo.y + (float(b) + 0.5f) / float(m) * size.y)), 0, height - 1)};
  }
};

// The billboards of the cells still holding opacity, front to back (ties by cell index).
std::vector<Region> billboardRegions(const OpacityGrid& grid, const PixelCamera& cam) {
  const int width = cam.width(), height = cam.height();
  const glm::vec2 half = billboardHalfExtents(grid.cellSize, cam.right(), cam.up());
  std::vector<Region> regions;
  for (size_t c = 0; c < grid.cells.size(); ++c) {
    if (grid.transparency[c] >= 1.0f) continue;
    const glm::vec3 center = grid.cellCenter(c);
    const float z = cam.depth(center);
    if (z <= 1e-4f) continue;
    const glm::vec2 p = cam.project(center), h = half * cam.focalPixels() / z;
    Region r{int32_t(c), p - h, 2.0f * h, 0, 0, 0, 0, z};
    r.x0 = std::max(0, int(std::ceil(p.x - h.x - 0.5f)));
    r.y0 = std::max(0, int(std::ceil(p.y - h.y - 0.5f)));
    r.x1 = std::min(width, int(std::floor(p.x + h.x - 0.5f)) + 1);
    r.y1 = std::min(height, int(std::floor(p.y + h.y - 0.5f)) + 1);
    regions.push_back(r);
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const Region& a, const Region& b) { return a.depth < b.depth; });
  return regions;
}

// The pure-foreground colour (Eq. 3: premultiplied / α) of a pixel, 8-bit sRGB.
void pureColour(const ImageRgbaF& image, int x, int y, uint8_t* out) {
  const float* p = image.at(x, y);
  for (int c = 0; c < 3; ++c)
    out[c] = p[3] > 1e-4f ? encodeSrgb8(std::clamp(p[c] / p[3], 0.0f, 1.0f)) : 0;
}

// Texels without alpha take the alpha-weighted mean colour of the others, so bilinear lookups
// near a billboard's edge blend towards its own colour, not towards black.
void fillTransparentTexels(std::vector<uint8_t>& rgba) {
  double sum[3] = {0, 0, 0}, weight = 0.0;
  for (size_t t = 0; t < rgba.size(); t += 4) {
    for (int c = 0; c < 3; ++c) sum[c] += double(rgba[t + c]) * rgba[t + 3];
    weight += rgba[t + 3];
  }
  if (weight <= 0.0) return;
  for (size_t t = 0; t < rgba.size(); t += 4)
    if (rgba[t + 3] == 0)
      for (int c = 0; c < 3; ++c) rgba[t + c] = uint8_t(std::lround(sum[c] / weight));
}

// kPartition, one view. Per pixel, the cells its ray crosses and each one's share of α_p.
struct PixelShares {
  std::vector<uint32_t> start;  // pixels + 1 offsets into the entries
  std::vector<int32_t> cell;
  std::vector<float> alpha;    // a_c
  std::vector<float> visible;  // a_c · Π_front (1 − a)
  // Pixels with α_p but no cell on their ray: shared among the billboards covering them.
  std::vector<float> fallbackExponent;  // per pixel: s with a_c = 1 − t_c^s, 0 when unused
};

PixelShares pixelShares(const OpacityGrid& grid, const OpacityView& view, float frontEmphasis) {
  const PixelCamera& cam = view.camera;
  const int width = cam.width(), height = cam.height();
  PixelShares shares;
  shares.start.assign(size_t(width) * height + 1, 0);
  shares.fallbackExponent.assign(size_t(width) * height, 0.0f);
  std::vector<RaySegment> segments;
  std::vector<float> depths;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t pixel = size_t(y) * width + x;
      shares.start[pixel] = uint32_t(shares.cell.size());
      const float alpha = std::clamp(view.image->at(x, y)[3], 0.0f, 1.0f);
      if (alpha < 1.0f / 512.0f) continue;
      const float tp = std::max(1.0f - alpha, 1e-3f);
      double total = 0.0;
      if (traceRay(grid, cam, float(x) + 0.5f, float(y) + 0.5f, segments)) {
        depths.clear();
        double front = 0.0;
        for (const RaySegment& s : segments) {
          const double depth = -std::log(grid.transparency[s.cell]) * s.length;
          depths.push_back(float(depth * std::exp(-frontEmphasis * front)));
          front += depth;
          total += depths.back();
        }
      }
      if (total < 1e-9) {
        shares.fallbackExponent[pixel] = -1.0f;  // marked; the exponent needs the billboards
        continue;
      }
      const double scale = -std::log(double(tp)) / total;
      double front = 1.0;
      for (size_t i = 0; i < segments.size(); ++i) {
        const float a = float(1.0 - std::exp(-scale * depths[i]));
        shares.cell.push_back(segments[i].cell);
        shares.alpha.push_back(a);
        shares.visible.push_back(float(a * front));
        front *= 1.0 - a;
      }
    }
  }
  shares.start.back() = uint32_t(shares.cell.size());
  return shares;
}

// The fallback pixels' exponent: their α_p spread over every billboard covering them by each
// cell's optical depth −log t_c (the rays missed the cells the hull kept for them).
void fallbackExponents(const OpacityGrid& grid, const OpacityView& view,
                       const std::vector<Region>& regions, PixelShares& shares) {
  const int width = view.camera.width();
  std::vector<double> depth(shares.fallbackExponent.size(), 0.0);
  for (const Region& r : regions)
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x)
        if (shares.fallbackExponent[size_t(y) * width + x] < 0.0f)
          depth[size_t(y) * width + x] -= std::log(double(grid.transparency[r.cell]));
  for (size_t p = 0; p < depth.size(); ++p) {
    if (shares.fallbackExponent[p] >= 0.0f) continue;
    const int x = int(p % size_t(width)), y = int(p / size_t(width));
    const double tp = std::max(1.0 - double(view.image->at(x, y)[3]), 1e-3);
    shares.fallbackExponent[p] = depth[p] > 0.0 ? float(std::log(tp) / -depth[p]) : 0.0f;
  }
}

std::vector<Tile> partitionTextures(const OpacityGrid& grid, const OpacityView& view,
                                    const TextureSettings& settings) {
  const PixelCamera& cam = view.camera;
  const int width = cam.width(), height = cam.height(), m = settings.texels;
  const std::vector<Region> regions = billboardRegions(grid, cam);
  PixelShares shares = pixelShares(grid, view, settings.frontEmphasis);
  fallbackExponents(grid, view, regions, shares);
  std::vector<Tile> tiles;
  for (const Region& r : regions) {
    Tile tile{r.cell, std::vector<uint8_t>(size_t(m) * m * 4, 0)};
    float mostVisible = 0.0f;
    const float tc = grid.transparency[r.cell];
    for (int b = 0; b < m; ++b) {
      for (int a = 0; a < m; ++a) {
        const glm::ivec2 p = r.pixelOf(a, b, m, width, height);
        const size_t pixel = size_t(p.y) * width + p.x;
        float alpha = 0.0f, visible = 0.0f;
        for (uint32_t e = shares.start[pixel]; e < shares.start[pixel + 1]; ++e) {
          if (shares.cell[e] != r.cell) continue;
          alpha = shares.alpha[e], visible = shares.visible[e];
          break;
        }
        if (shares.fallbackExponent[pixel] > 0.0f)
          visible = alpha = 1.0f - std::pow(tc, shares.fallbackExponent[pixel]);
        uint8_t* texel = &tile.rgba[(size_t(b) * m + a) * 4];
        texel[3] = uint8_t(std::lround(alpha * 255.0f));
        if (texel[3] == 0) continue;
        pureColour(*view.image, p.x, p.y, texel);
        mostVisible = std::max(mostVisible, visible);
      }
    }
    if (mostVisible <= 0.0f) continue;  // empty
    tile.hidden = mostVisible < settings.hiddenCutoff;
    fillTransparentTexels(tile.rgba);
    tiles.push_back(std::move(tile));
  }
  return tiles;
}

// kPaper, one view, in front-to-back cell order.
std::vector<Tile> paperTextures(const OpacityGrid& grid, const OpacityView& view,
                                const TextureSettings& settings) {
  const PixelCamera& cam = view.camera;
  const int width = cam.width(), height = cam.height(), m = settings.texels;
  const ImageRgbaF& image = *view.image;
  // The copy C_i of the pure-foreground colour, 8-bit sRGB for OpenCV's inpainting.
  cv::Mat copy(height, width, CV_8UC3);
  std::vector<float> tCurr(size_t(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      pureColour(image, x, y, copy.at<cv::Vec3b>(y, x).val);
      tCurr[size_t(y) * width + x] = 1.0f - image.at(x, y)[3];
    }
  }
  const std::vector<Region> regions = billboardRegions(grid, cam);  // front to back (§6)
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
  for (const Region& r : regions) {
    const float tc = grid.transparency[r.cell];
    for (int b = 0; b < m; ++b) {
      for (int a = 0; a < m; ++a) {
        const glm::ivec2 p = r.pixelOf(a, b, m, width, height);
        const size_t pixel = size_t(p.y) * width + p.x;
        const int t = b * m + a;
        texelPixel[t] = int(pixel);
        texelAge[t] = age[pixel];
        // Eq. 14: texels whose remaining transparency matches this cell's share score high.
        const float expected = std::pow(tc, float(std::max<uint16_t>(nCurr[pixel], 1)));
        importance[t] = 1.0f / (std::abs(tCurr[pixel] - expected) + 1e-6f);
      }
    }
    const std::vector<int> selected = selectTexels(texelAge, importance, tc);
    Tile tile{r.cell, std::vector<uint8_t>(size_t(texelCount) * 4, 0)};
    bool any = false;
    for (int t : selected) {
      const int pixel = texelPixel[t];
      const int x = pixel % width, y = pixel / width;
      uint8_t* texel = &tile.rgba[size_t(t) * 4];
      texel[3] = uint8_t(std::lround(std::clamp(image.at(x, y)[3], 0.0f, 1.0f) * 255.0f));
      const cv::Vec3b& colour = copy.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) texel[c] = colour[c];
      any = any || texel[3] > 0;
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
    if (!any) continue;
    fillTransparentTexels(tile.rgba);
    tiles.push_back(std::move(tile));
  }
  return tiles;
}

}  // namespace

ViewTextures generateViewTextures(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                                  const TextureSettings& settings) {
  std::vector<std::vector<Tile>> perView(views.size());
  tbb::parallel_for(size_t(0), views.size(), [&](size_t v) {
    perView[v] = settings.selection == TexelSelection::kPartition
                     ? partitionTextures(grid, views[v], settings)
                     : paperTextures(grid, views[v], settings);
  });
  ViewTextures textures;
  textures.texels = settings.texels;
  textures.views = int(views.size());
  textures.cells = int(grid.cells.size());
  textures.tile.assign(size_t(textures.views) * textures.cells, kNoTile);
  // Tiles stored cell by cell, each cell's in view order: a cell's textures are contiguous, so
  // the draw finds them from the cell's first tile and a mask of the views that have one.
  std::vector<std::vector<std::pair<size_t, Tile*>>> ofCell(size_t(textures.cells));
  size_t produced = 0;
  for (size_t v = 0; v < perView.size(); ++v) {
    produced += perView[v].size();
    for (Tile& tile : perView[v]) {
      if (tile.hidden) {
        ++textures.hiddenTiles;
        continue;
      }
      ofCell[size_t(tile.cell)].emplace_back(v, &tile);
    }
  }
  uint32_t next = 0;
  for (size_t c = 0; c < ofCell.size(); ++c) {
    for (const auto& [v, tile] : ofCell[c]) {  // views ascending: perView is walked in order
      textures.tile[v * textures.cells + c] = next++;
      textures.rgba.insert(textures.rgba.end(), tile->rgba.begin(), tile->rgba.end());
    }
  }
  textures.emptyTiles = textures.tile.size() - produced;
  return textures;
}

TileAtlas layOutTiles(const std::vector<uint8_t>& rgba, int texels, int maxPageSize) {
  TileAtlas atlas;
  atlas.texels = texels;
  const size_t tileBytes = size_t(texels) * texels * 4;
  const size_t tiles = rgba.size() / tileBytes;
  // Page side a multiple of both M and the 4×4 blocks of S3TC.
  const int unit = std::lcm(texels, 4);
  const int largest = std::max(unit, maxPageSize / unit * unit);
  int pageSize = unit;
  while (pageSize < largest && size_t(pageSize / texels) * size_t(pageSize / texels) < tiles)
    pageSize = std::min(largest, pageSize * 2);
  atlas.pageSize = pageSize;
  atlas.tilesPerRow = pageSize / texels;
  const size_t perPage = size_t(atlas.tilesPerPage());
  const size_t pages = std::max<size_t>(1, (tiles + perPage - 1) / perPage);
  atlas.pages.assign(pages, ImageRgba8(pageSize, pageSize));
  for (size_t i = 0; i < tiles; ++i) {
    ImageRgba8& page = atlas.pages[i / perPage];
    const size_t slot = i % perPage;
    const int x0 = int(slot % size_t(atlas.tilesPerRow)) * texels;
    const int y0 = int(slot / size_t(atlas.tilesPerRow)) * texels;
    for (int b = 0; b < texels; ++b)
      std::copy_n(&rgba[i * tileBytes + size_t(b) * texels * 4], size_t(texels) * 4,
                  page.at(x0, y0 + b));
  }
  return atlas;
}

}  // namespace canopy
