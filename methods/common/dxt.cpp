#include "methods/common/dxt.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "common/error.h"

namespace canopy {

Compression parseCompression(const std::string& name) {
  if (name == "none") return Compression::kNone;
  if (name == "dxt1") return Compression::kDxt1;
  if (name == "dxt5") return Compression::kDxt5;
  throwInputError(R"(parameter 'compression' = '{}' must be "none", "dxt1" or "dxt5")", name);
}

bool driverHasS3tc() {
  const gl::Api& g = gl::api();
  GLint count = 0;
  g.GetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const auto* name =
        reinterpret_cast<const char*>(g.GetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (name && std::strcmp(name, "GL_EXT_texture_compression_s3tc") == 0) return true;
  }
  return false;
}

void requireS3tcFor(Compression compression) {
  if (compression != Compression::kNone && !driverHasS3tc()) {
    throwInputError("parameter 'compression': this OpenGL driver has no S3TC; use \"none\"");
  }
}

GLenum srgbInternalFormat(Compression compression) {
  switch (compression) {
    case Compression::kDxt1:
      return 0x8C4D;  // GL_COMPRESSED_SRGB_ALPHA_S3TC_DXT1_EXT
    case Compression::kDxt5:
      return 0x8C4F;  // GL_COMPRESSED_SRGB_ALPHA_S3TC_DXT5_EXT
    case Compression::kNone:
      break;
  }
  return GL_SRGB8_ALPHA8;
}

namespace {

uint16_t toRgb565(const glm::vec3& c) {
  const auto r = static_cast<uint16_t>(std::lround(std::clamp(c.r, 0.0f, 255.0f) * 31.0f / 255.0f));
  const auto g = static_cast<uint16_t>(std::lround(std::clamp(c.g, 0.0f, 255.0f) * 63.0f / 255.0f));
  const auto b = static_cast<uint16_t>(std::lround(std::clamp(c.b, 0.0f, 255.0f) * 31.0f / 255.0f));
  return static_cast<uint16_t>((r << 11) | (g << 5) | b);
}

glm::vec3 fromRgb565(uint16_t v) {
  return {float((v >> 11) & 31) * 255.0f / 31.0f, float((v >> 5) & 63) * 255.0f / 63.0f,
          float(v & 31) * 255.0f / 31.0f};
}

// BC1 colour block: endpoints at the extremes of the texels' projection on their principal axis.
// `punchThrough`: texels with alpha < 128 use index 3 of the three-colour mode (transparent).
void encodeColorBlock(const uint8_t texels[16][4], bool punchThrough, uint8_t* out) {
  glm::vec3 mean(0.0f);
  int opaque = 0;
  for (int i = 0; i < 16; ++i) {
    if (punchThrough && texels[i][3] < 128) continue;
    mean += glm::vec3(texels[i][0], texels[i][1], texels[i][2]);
    ++opaque;
  }
  uint16_t c0 = 0, c1 = 0;
  if (opaque > 0) {
    mean /= float(opaque);
    float cov[6] = {0, 0, 0, 0, 0, 0};
    for (int i = 0; i < 16; ++i) {
      if (punchThrough && texels[i][3] < 128) continue;
      const glm::vec3 d = glm::vec3(texels[i][0], texels[i][1], texels[i][2]) - mean;
      cov[0] += d.r * d.r, cov[1] += d.r * d.g, cov[2] += d.r * d.b, cov[3] += d.g * d.g,
          cov[4] += d.g * d.b, cov[5] += d.b * d.b;
    }
    glm::vec3 axis(1.0f, 1.0f, 1.0f);
    for (int iteration = 0; iteration < 8; ++iteration) {  // power iteration
      const glm::vec3 next(cov[0] * axis.r + cov[1] * axis.g + cov[2] * axis.b,
                           cov[1] * axis.r + cov[3] * axis.g + cov[4] * axis.b,
                           cov[2] * axis.r + cov[4] * axis.g + cov[5] * axis.b);
      const float length = glm::length(next);
      if (length < 1e-6f) break;
      axis = next / length;
    }
    float lo = 1e9f, hi = -1e9f;
    for (int i = 0; i < 16; ++i) {
      if (punchThrough && texels[i][3] < 128) continue;
      const float t = glm::dot(glm::vec3(texels[i][0], texels[i][1], texels[i][2]) - mean, axis);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    c0 = toRgb565(mean + axis * hi);
    c1 = toRgb565(mean + axis * lo);
  }
  const bool threeColor = punchThrough && opaque < 16;
  // Four-colour mode needs c0 > c1, three-colour mode c0 <= c1.
  if ((threeColor && c0 > c1) || (!threeColor && c0 < c1)) std::swap(c0, c1);
  if (!threeColor && c0 == c1) {
    if (c1 > 0)
      --c1;
    else
      ++c0;
  }
  glm::vec3 palette[4] = {fromRgb565(c0), fromRgb565(c1), {}, {}};
  if (threeColor) {
    palette[2] = (palette[0] + palette[1]) * 0.5f;
  } else {
    palette[2] = (palette[0] * 2.0f + palette[1]) / 3.0f;
    palette[3] = (palette[0] + palette[1] * 2.0f) / 3.0f;
  }
  uint32_t indices = 0;
  for (int i = 0; i < 16; ++i) {
    uint32_t best = 0;
    if (threeColor && texels[i][3] < 128) {
      best = 3;
    } else {
      const glm::vec3 c(texels[i][0], texels[i][1], texels[i][2]);
      float bestDistance = 1e30f;
      for (uint32_t k = 0; k < (threeColor ? 3u : 4u); ++k) {
        const glm::vec3 d = c - palette[k];
        const float distance = glm::dot(d, d);
        if (distance < bestDistance) bestDistance = distance, best = k;
      }
    }
    indices |= best << (2 * i);
  }
  out[0] = uint8_t(c0 & 255), out[1] = uint8_t(c0 >> 8), out[2] = uint8_t(c1 & 255),
  out[3] = uint8_t(c1 >> 8);
  std::memcpy(out + 4, &indices, 4);  // little-endian host
}

// BC3 alpha block: 8-value interpolation between the block's min and max alpha.
void encodeAlphaBlock(const uint8_t texels[16][4], uint8_t* out) {
  uint8_t a0 = 0, a1 = 255;
  for (int i = 0; i < 16; ++i) a0 = std::max(a0, texels[i][3]), a1 = std::min(a1, texels[i][3]);
  out[0] = a0;
  out[1] = a1;
  float palette[8];
  palette[0] = a0, palette[1] = a1;
  for (int k = 1; k < 7; ++k) palette[k + 1] = ((7 - k) * a0 + k * a1) / 7.0f;
  uint64_t bits = 0;
  for (int i = 0; i < 16; ++i) {
    uint64_t best = 0;
    float bestDistance = 1e30f;
    for (uint64_t k = 0; k < (a0 > a1 ? 8u : 1u); ++k) {
      const float distance = std::abs(palette[k] - texels[i][3]);
      if (distance < bestDistance) bestDistance = distance, best = k;
    }
    bits |= best << (3 * i);
  }
  for (int b = 0; b < 6; ++b) out[2 + b] = uint8_t((bits >> (8 * b)) & 255);
}

}  // namespace

std::vector<uint8_t> compressImage(const ImageRgba8& image, Compression compression) {
  const int blocksX = (image.width + 3) / 4, blocksY = (image.height + 3) / 4;
  const size_t blockBytes = compression == Compression::kDxt5 ? 16 : 8;
  std::vector<uint8_t> out(size_t(blocksX) * blocksY * blockBytes);
  for (int by = 0; by < blocksY; ++by) {
    for (int bx = 0; bx < blocksX; ++bx) {
      uint8_t texels[16][4];
      for (int i = 0; i < 16; ++i) {
        const int x = std::min(image.width - 1, bx * 4 + i % 4),
                  y = std::min(image.height - 1, by * 4 + i / 4);
        std::memcpy(texels[i], image.at(x, y), 4);
      }
      uint8_t* block = &out[(size_t(by) * blocksX + bx) * blockBytes];
      if (compression == Compression::kDxt5) {
        encodeAlphaBlock(texels, block);
        encodeColorBlock(texels, false, block + 8);
      } else {
        encodeColorBlock(texels, true, block);
      }
    }
  }
  return out;
}

}  // namespace canopy
