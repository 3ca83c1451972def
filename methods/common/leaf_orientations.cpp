#include "methods/common/leaf_orientations.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "common/error.h"

namespace canopy {
namespace {
constexpr float kTwoPi = 6.28318530718f;
}

uint32_t orientedImageIndex(const Leaf& leaf, const Billboard& billboard,
                            const OrientationBins& bins) {
  const glm::vec2 along(glm::dot(leaf.axisV, billboard.axisU),
                        glm::dot(leaf.axisV, billboard.axisV));
  const float angle = std::atan2(along.y, along.x);
  const int rotation =
      ((static_cast<int>(std::lround(angle / (kTwoPi / bins.rotations))) % bins.rotations) +
       bins.rotations) %
      bins.rotations;
  const float facing = glm::dot(leaf.normal, billboard.normal);
  const int tilt =
      std::clamp(static_cast<int>(std::ceil(std::abs(facing) * bins.tilts)) - 1, 0, bins.tilts - 1);
  const int back = facing < 0.0f ? 1 : 0;
  return static_cast<uint32_t>(
      ((int(leaf.texture) * 2 + back) * bins.tilts + tilt) * bins.rotations + rotation);
}

uint32_t orientedImageCount(size_t leafTextures, const OrientationBins& bins) {
  return static_cast<uint32_t>(leafTextures * 2 * bins.tilts * bins.rotations);
}

std::vector<ImageRgba8> buildOrientedLeafImages(const Tree& tree, const LeafImageSampler& sampler,
                                                const OrientationBins& bins, int size) {
  // Shape of each texture's leaves: from the first leaf that uses it.
  std::vector<const Leaf*> shape(tree.leafTextures.size(), nullptr);
  for (const Leaf& leaf : tree.leaves) {
    if (!shape[leaf.texture]) shape[leaf.texture] = &leaf;
  }
  const uint32_t count = orientedImageCount(tree.leafTextures.size(), bins);
  std::vector<ImageRgba8> images(count);
  constexpr int kSupersample = 4;
  tbb::parallel_for(uint32_t(0), count, [&](uint32_t index) {
    const int rotation = int(index % bins.rotations);
    const int tilt = int((index / bins.rotations) % bins.tilts);
    const bool back = (index / (bins.rotations * bins.tilts)) % 2 == 1;
    const uint32_t texture = index / (bins.rotations * bins.tilts * 2);
    ImageRgba8& image = images[index];
    image = ImageRgba8(size, size);
    const Leaf* leaf = shape[texture];
    if (!leaf) return;  // a texture no leaf uses: stays transparent
    const float length = 2.0f * std::max(leaf->halfExtents.x, leaf->halfExtents.y);
    const float halfAlong = leaf->halfExtents.y / length, halfAcross = leaf->halfExtents.x / length;
    const float width = float(tilt + 1) / float(bins.tilts);
    const float angle = float(rotation) * kTwoPi / float(bins.rotations);
    const glm::vec2 along(std::cos(angle), std::sin(angle)), across(-along.y, along.x);
    const glm::ivec2 texSize = sampler.size(texture);
    const float footprint =
        float(std::max(texSize.x, texSize.y)) / float(size * kSupersample) / std::max(width, 0.1f);
    image = renderCoverageImage(size, kSupersample, [&](glm::vec2 unit) {
      const glm::vec2 q = unit - 0.5f;
      const float b = glm::dot(q, along) / halfAlong;              // leaf v' in [−1, 1]
      const float a = glm::dot(q, across) / (halfAcross * width);  // leaf u' in [−1, 1]
      if (std::abs(a) > 1.0f || std::abs(b) > 1.0f) return glm::vec4(0.0f);
      const glm::vec2 uv =
          leaf->uvMin + (glm::vec2(a, b) + 1.0f) * 0.5f * (leaf->uvMax - leaf->uvMin);
      return sampler.sample(texture, back, uv, footprint);
    });
  });
  return images;
}

}  // namespace canopy
