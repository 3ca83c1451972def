#include "methods/common/mipmaps.h"

#include <algorithm>
#include <cmath>

#include <glm/vec4.hpp>

#include "common/error.h"

namespace canopy {
namespace {

double passingFraction(const std::vector<float>& alpha, float scale, float threshold) {
  size_t passing = 0;
  for (float a : alpha) passing += a * scale >= threshold ? 1 : 0;
  return alpha.empty() ? 0.0 : double(passing) / double(alpha.size());
}

}  // namespace

std::vector<ImageRgba8> buildCoveragePreservingMips(const ImageRgba8& base, float alphaThreshold) {
  std::vector<ImageRgba8> levels{base};
  std::vector<float> baseAlpha(size_t(base.width) * base.height);
  for (size_t i = 0; i < baseAlpha.size(); ++i) baseAlpha[i] = base.pixels[i * 4 + 3] / 255.0f;
  const double target = passingFraction(baseAlpha, 1.0f, alphaThreshold);
  // Linear, straight-alpha float copy of the current level, filtered down level by level.
  int width = base.width, height = base.height;
  std::vector<glm::vec4> current(baseAlpha.size());
  for (size_t i = 0; i < current.size(); ++i) {
    const uint8_t* p = &base.pixels[i * 4];
    current[i] = {srgbToLinear(p[0] / 255.0f), srgbToLinear(p[1] / 255.0f),
                  srgbToLinear(p[2] / 255.0f), baseAlpha[i]};
  }
  while (width > 1 || height > 1) {
    const int w = std::max(1, width / 2), h = std::max(1, height / 2);
    std::vector<glm::vec4> next(size_t(w) * h);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        glm::vec3 color(0.0f), unweighted(0.0f);
        float alpha = 0.0f;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const glm::vec4 t = current[size_t(std::min(height - 1, y * 2 + dy)) * width +
                                        std::min(width - 1, x * 2 + dx)];
            color += glm::vec3(t) * t.a;
            unweighted += glm::vec3(t);
            alpha += t.a;
          }
        }
        next[size_t(y) * w + x] = alpha > 0.0f ? glm::vec4(color / alpha, alpha * 0.25f)
                                               : glm::vec4(unweighted * 0.25f, 0.0f);
      }
    }
    width = w;
    height = h;
    current = std::move(next);
    // Bisect the alpha scale that brings the passing fraction back to level 0's.
    std::vector<float> alpha(current.size());
    for (size_t i = 0; i < current.size(); ++i) alpha[i] = current[i].a;
    float lo = 1.0f, hi = 1.0f;
    if (passingFraction(alpha, 1.0f, alphaThreshold) < target) {
      hi = 64.0f;
      for (int step = 0; step < 24; ++step) {
        const float mid = 0.5f * (lo + hi);
        (passingFraction(alpha, mid, alphaThreshold) < target ? lo : hi) = mid;
      }
    }
    ImageRgba8 level(width, height);
    for (size_t i = 0; i < current.size(); ++i) {
      uint8_t* out = &level.pixels[i * 4];
      for (int c = 0; c < 3; ++c) out[c] = encodeSrgb8(current[i][c]);
      out[3] =
          static_cast<uint8_t>(std::lround(std::clamp(current[i].a * hi, 0.0f, 1.0f) * 255.0f));
    }
    levels.push_back(std::move(level));
  }
  return levels;
}

}  // namespace canopy

namespace canopy {

gl::Texture uploadAlphaTestedTexture(gl::Device& device, const ImageRgba8& image, bool mipmaps,
                                     const char* label, Compression compression) {
  requireS3tcFor(compression);
  gl::Texture texture = device.createTexture({GL_TEXTURE_2D, image.width, image.height, 1,
                                              srgbInternalFormat(compression), mipmaps,
                                              gl::MemoryCategory::kTexture, label});
  const std::vector<ImageRgba8> levels =
      mipmaps ? buildCoveragePreservingMips(image) : std::vector<ImageRgba8>{image};
  for (size_t level = 0; level < levels.size(); ++level) {
    if (compression == Compression::kNone) {
      device.uploadTextureLevel(texture, static_cast<int>(level), GL_RGBA, GL_UNSIGNED_BYTE,
                                levels[level].pixels.data());
    } else {
      device.uploadCompressedLevel(texture, static_cast<int>(level), 0,
                                   compressImage(levels[level], compression));
    }
  }
  gl::setTextureSampling(texture, true, false);
  return texture;
}

}  // namespace canopy
