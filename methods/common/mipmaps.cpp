#include "methods/common/mipmaps.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/vec4.hpp>

#include "common/error.h"

namespace canopy {
namespace {

constexpr int kBins = 4096;  // alpha histogram resolution of the area search
using Histogram = std::array<uint64_t, kBins + 1>;

// Histogram of the filtered alpha (times `scale`, before any binary cut) at 2×2 positions per
// texel: bin b counts samples whose value is at least b / kBins. `binary` cuts each texel at
// 0.5 / scale first, so the histogram then only tells passing (last bin) from failing.
Histogram filteredAlphaHistogram(const std::vector<float>& alpha, int width, int height,
                                 float scale, bool binary) {
  std::vector<Histogram> rows(size_t(height) * 2);
  tbb::parallel_for(0, height * 2, [&](int sy) {
    Histogram& histogram = rows[size_t(sy)];
    histogram.fill(0);
    const auto at = [&](int x, int y) {
      const float a =
          alpha[size_t(std::clamp(y, 0, height - 1)) * width + std::clamp(x, 0, width - 1)] * scale;
      return binary ? (a >= 0.5f ? 1.0f : 0.0f) : std::min(a, 1.0f);
    };
    // Sample positions (k + 0.5) / 2 in texel units; texel centres sit at i + 0.5.
    const float fy = (sy + 0.5f) * 0.5f - 0.5f;
    const int y0 = static_cast<int>(std::floor(fy));
    const float ty = fy - float(y0);
    for (int sx = 0; sx < width * 2; ++sx) {
      const float fx = (sx + 0.5f) * 0.5f - 0.5f;
      const int x0 = static_cast<int>(std::floor(fx));
      const float tx = fx - float(x0);
      const float value = (at(x0, y0) * (1 - tx) + at(x0 + 1, y0) * tx) * (1 - ty) +
                          (at(x0, y0 + 1) * (1 - tx) + at(x0 + 1, y0 + 1) * tx) * ty;
      ++histogram[static_cast<size_t>(std::clamp(value, 0.0f, 1.0f) * kBins)];
    }
  });
  Histogram total{};
  for (const Histogram& row : rows)
    for (size_t b = 0; b < total.size(); ++b) total[b] += row[b];
  return total;
}

double passingShare(const Histogram& histogram, float threshold) {
  uint64_t passing = 0, all = 0;
  const auto first = static_cast<size_t>(std::ceil(threshold * kBins));
  for (size_t b = 0; b < histogram.size(); ++b) {
    all += histogram[b];
    if (b >= first) passing += histogram[b];
  }
  return all ? double(passing) / double(all) : 0.0;
}

std::vector<float> alphaOf(const ImageRgba8& image) {
  std::vector<float> alpha(size_t(image.width) * image.height);
  for (size_t i = 0; i < alpha.size(); ++i) alpha[i] = image.pixels[i * 4 + 3] / 255.0f;
  return alpha;
}

// The alpha scale that makes the filtered, alpha-tested area `target`, bisected on a log scale
// (the area grows with the scale; stored alpha saturates at 1, so no closed form holds).
float areaPreservingScale(const std::vector<float>& alpha, int width, int height, double target,
                          bool binary) {
  if (target <= 0.0) return 1.0f;
  const auto area = [&](float scale) {
    return passingShare(filteredAlphaHistogram(alpha, width, height, scale, binary), 0.5f);
  };
  float lo = 1.0f / 16.0f, hi = 64.0f;
  if (area(hi) <= target) return hi;
  if (area(lo) >= target) return lo;
  for (int step = 0; step < 16; ++step) {
    const float mid = std::sqrt(lo * hi);
    (area(mid) < target ? lo : hi) = mid;
  }
  // The scale whose area is nearer the target (areas move in steps on small levels).
  return std::abs(area(lo) - target) < std::abs(area(hi) - target) ? lo : hi;
}

}  // namespace

double alphaTestedArea(const ImageRgba8& image, bool binary) {
  return passingShare(
      filteredAlphaHistogram(alphaOf(image), image.width, image.height, 1.0f, binary), 0.5f);
}

std::vector<ImageRgba8> buildCoveragePreservingMips(const ImageRgba8& base, Compression compression,
                                                    bool mipmaps, CoverageTarget coverage) {
  const bool binary = compression == Compression::kDxt1;
  std::vector<float> alpha = alphaOf(base);
  double target = 0.0;
  if (coverage == CoverageTarget::kLevelZeroTest) {
    target = alphaTestedArea(base, binary);
  } else {
    for (float a : alpha) target += a;
    target = alpha.empty() ? 0.0 : target / double(alpha.size());
  }
  // Linear, straight-alpha float copy of the current level, filtered down level by level.
  int width = base.width, height = base.height;
  std::vector<glm::vec4> current(alpha.size());
  for (size_t i = 0; i < current.size(); ++i) {
    const uint8_t* p = &base.pixels[i * 4];
    current[i] = {srgbToLinear(p[0] / 255.0f), srgbToLinear(p[1] / 255.0f),
                  srgbToLinear(p[2] / 255.0f), alpha[i]};
  }
  std::vector<ImageRgba8> levels;
  while (true) {
    for (size_t i = 0; i < current.size(); ++i) alpha[i] = current[i].a;
    const bool keep = levels.empty() && coverage == CoverageTarget::kLevelZeroTest;
    const float scale = keep ? 1.0f : areaPreservingScale(alpha, width, height, target, binary);
    ImageRgba8 level(width, height);
    for (size_t i = 0; i < current.size(); ++i) {
      uint8_t* out = &level.pixels[i * 4];
      if (levels.empty()) {
        std::copy_n(&base.pixels[i * 4], 3, out);  // level 0 keeps its colour bytes
      } else {
        for (int c = 0; c < 3; ++c) out[c] = encodeSrgb8(current[i][c]);
      }
      out[3] = static_cast<uint8_t>(std::lround(std::clamp(alpha[i] * scale, 0.0f, 1.0f) * 255.0f));
    }
    levels.push_back(std::move(level));
    if (!mipmaps || (width == 1 && height == 1)) break;
    const int w = std::max(1, width / 2), h = std::max(1, height / 2);
    std::vector<glm::vec4> next(size_t(w) * h);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        glm::vec3 color(0.0f), unweighted(0.0f);
        float sum = 0.0f;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const glm::vec4 t = current[size_t(std::min(height - 1, y * 2 + dy)) * width +
                                        std::min(width - 1, x * 2 + dx)];
            color += glm::vec3(t) * t.a;
            unweighted += glm::vec3(t);
            sum += t.a;
          }
        }
        next[size_t(y) * w + x] =
            sum > 0.0f ? glm::vec4(color / sum, sum * 0.25f) : glm::vec4(unweighted * 0.25f, 0.0f);
      }
    }
    width = w;
    height = h;
    current = std::move(next);
    alpha.resize(current.size());
  }
  return levels;
}

namespace {

gl::Texture uploadLevels(gl::Device& device, const std::vector<ImageRgba8>& layers, GLenum target,
                         bool mipmaps, const char* label, Compression compression,
                         CoverageTarget coverage) {
  requireS3tcFor(compression);
  const int width = layers.empty() ? 1 : layers[0].width;
  const int height = layers.empty() ? 1 : layers[0].height;
  for (const ImageRgba8& layer : layers) {
    if (layer.width != width || layer.height != height)
      throw std::logic_error("uploadAlphaTestedArray: layers differ in size");
  }
  gl::Texture texture = device.createTexture(
      {target, width, height, static_cast<int>(std::max<size_t>(layers.size(), 1)),
       srgbInternalFormat(compression), mipmaps, gl::MemoryCategory::kTexture, label});
  std::vector<std::vector<ImageRgba8>> chains(layers.size());
  tbb::parallel_for(size_t(0), layers.size(), [&](size_t layer) {
    chains[layer] = buildCoveragePreservingMips(layers[layer], compression, mipmaps, coverage);
  });
  for (size_t layer = 0; layer < chains.size(); ++layer) {
    for (size_t level = 0; level < chains[layer].size(); ++level) {
      const ImageRgba8& image = chains[layer][level];
      const auto l = static_cast<int>(level);
      if (compression != Compression::kNone) {
        device.uploadCompressedLevel(texture, l, static_cast<int>(layer),
                                     compressImage(image, compression));
      } else if (target == GL_TEXTURE_2D_ARRAY) {
        device.uploadTextureLayer(texture, static_cast<int>(layer), GL_RGBA, GL_UNSIGNED_BYTE,
                                  image.pixels.data(), l);
      } else {
        device.uploadTextureLevel(texture, l, GL_RGBA, GL_UNSIGNED_BYTE, image.pixels.data());
      }
    }
  }
  gl::setTextureSampling(texture, true, false);
  return texture;
}

}  // namespace

gl::Texture uploadAlphaTestedTexture(gl::Device& device, const ImageRgba8& image, bool mipmaps,
                                     const char* label, Compression compression,
                                     CoverageTarget target) {
  return uploadLevels(device, {image}, GL_TEXTURE_2D, mipmaps, label, compression, target);
}

gl::Texture uploadAlphaTestedArray(gl::Device& device, const std::vector<ImageRgba8>& layers,
                                   bool mipmaps, const char* label, Compression compression) {
  return uploadLevels(device, layers, GL_TEXTURE_2D_ARRAY, mipmaps, label, compression,
                      CoverageTarget::kCoveredArea);
}

}  // namespace canopy
