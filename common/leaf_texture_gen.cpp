#include "common/leaf_texture_gen.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace canopy {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kPetioleEnd = 0.08f;  // v where the blade starts

uint32_t hashInts(uint32_t x, uint32_t y, uint32_t seed) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return h;
}

// Smooth value noise in [0, 1] at lattice spacing 1.
float valueNoise(float x, float y, uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  const auto ix = static_cast<uint32_t>(static_cast<int32_t>(fx));
  const auto iy = static_cast<uint32_t>(static_cast<int32_t>(fy));
  auto corner = [&](uint32_t dx, uint32_t dy) {
    return float(hashInts(ix + dx, iy + dy, seed) & 0xffffu) / 65535.0f;
  };
  const float sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const float top = corner(0, 0) + (corner(1, 0) - corner(0, 0)) * sx;
  const float bottom = corner(0, 1) + (corner(1, 1) - corner(0, 1)) * sx;
  return top + (bottom - top) * sy;
}

// Half width of the blade at blade parameter t in [0, 1] (uv units).
float bladeHalfWidth(float t) {
  if (t <= 0.0f || t >= 1.0f) return 0.0f;
  return 0.44f * std::pow(std::sin(kPi * std::pow(t, 0.8f)), 0.85f);
}

// Signed distance-like measure (uv units) to the leaf outline; > 0 inside.
float insideMeasure(float u, float v) {
  const float across = std::abs(u - 0.5f);
  if (v < kPetioleEnd) return v > 0.0f ? 0.014f - across : -1.0f;
  const float t = (v - kPetioleEnd) / (0.98f - kPetioleEnd);
  return bladeHalfWidth(t) - across;
}

// 1 on the midrib and on the veins, falling to 0 a texel or two away.
float venation(float u, float v, float texel) {
  const float across = std::abs(u - 0.5f);
  const float midribWidth = 0.012f * (1.0f - v) + 0.003f;
  const float midrib = std::clamp(1.0f - (across - midribWidth) / texel, 0.0f, 1.0f);
  // Veins leave the midrib towards the tip: lines v - 0.55·across = const, 9 pairs.
  const float phase = (v - 0.55f * across) * 9.0f;
  const float distance = std::abs(phase - std::round(phase)) / 9.0f;
  const float vein = std::clamp(1.0f - (distance - 0.003f) / texel, 0.0f, 1.0f) *
                     std::clamp((0.4f - across) * 8.0f, 0.0f, 1.0f);
  return std::max(midrib, 0.7f * vein);
}

}  // namespace

LeafTexture drawLeafTexture(int size, uint32_t variant) {
  LeafTexture texture;
  texture.name = "procedural_leaf_" + std::to_string(variant);
  texture.front = ImageRgba8(size, size);
  texture.back = ImageRgba8(size, size);
  texture.normalMap = ImageRgba8(size, size);
  const float texel = 1.0f / float(size);
  // Variants differ in hue and in the noise seed.
  const glm::vec3 baseGreen =
      variant % 2 == 0 ? glm::vec3(0.20f, 0.42f, 0.10f) : glm::vec3(0.28f, 0.45f, 0.08f);
  std::vector<float> height(size_t(size) * size, 0.0f);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const float u = (x + 0.5f) * texel, v = (y + 0.5f) * texel;
      const float alpha = std::clamp(insideMeasure(u, v) / texel + 0.5f, 0.0f, 1.0f);
      const float veins = venation(u, v, texel);
      const float mottle = valueNoise(u * 14.0f, v * 14.0f, variant) * 0.6f +
                           valueNoise(u * 40.0f, v * 40.0f, variant + 17) * 0.4f;
      const float edgeDarkening = std::clamp(insideMeasure(u, v) * 12.0f, 0.0f, 1.0f);
      glm::vec3 front = baseGreen * (0.75f + 0.45f * mottle) * (0.8f + 0.2f * edgeDarkening);
      front = glm::mix(front, glm::vec3(0.55f, 0.65f, 0.30f), 0.55f * veins);
      glm::vec3 back = glm::mix(front, glm::vec3(0.45f, 0.52f, 0.38f), 0.45f);
      back = glm::mix(back, glm::vec3(0.72f, 0.76f, 0.55f), 0.6f * veins);
      const auto toByte = [](float c) {
        return static_cast<uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
      };
      uint8_t* f = texture.front.at(x, y);
      uint8_t* b = texture.back.at(x, y);
      for (int c = 0; c < 3; ++c) {
        f[c] = toByte(front[c]);
        b[c] = toByte(back[c]);
      }
      f[3] = b[3] = toByte(alpha);
      height[size_t(y) * size + x] = -veins;  // veins are grooves on the upper side
    }
  }
  // Normal map from the height field by central differences (tangent space, z out of the leaf).
  const float strength = 2.0f;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      auto h = [&](int px, int py) {
        px = std::clamp(px, 0, size - 1);
        py = std::clamp(py, 0, size - 1);
        return height[size_t(py) * size + px];
      };
      const glm::vec3 n = glm::normalize(glm::vec3(-(h(x + 1, y) - h(x - 1, y)) * strength,
                                                   -(h(x, y + 1) - h(x, y - 1)) * strength, 1.0f));
      uint8_t* p = texture.normalMap.at(x, y);
      for (int c = 0; c < 3; ++c)
        p[c] = static_cast<uint8_t>(std::lround((n[c] * 0.5f + 0.5f) * 255.0f));
      p[3] = 255;
    }
  }
  return texture;
}

}  // namespace canopy
