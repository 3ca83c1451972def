#include "methods/common/leaf_images.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <map>
#include <tuple>

#include <glm/common.hpp>

#include "common/error.h"

namespace canopy {

LeafImages buildLeafImages(const Tree& tree, const LeafImageSampler& sampler, int size,
                           size_t maxImages) {
  // Rectangles equal to 1e-5 of the texture are one image.
  using Key = std::tuple<uint32_t, long, long, long, long>;
  const auto keyOf = [](const Leaf& leaf) {
    const auto q = [](float v) { return std::lround(double(v) * 1e5); };
    return Key{leaf.texture, q(leaf.uvMin.x), q(leaf.uvMin.y), q(leaf.uvMax.x), q(leaf.uvMax.y)};
  };
  std::map<Key, uint32_t> indexOf;
  std::vector<const Leaf*> first;
  LeafImages out;
  out.imageOfLeaf.reserve(tree.leaves.size());
  for (const Leaf& leaf : tree.leaves) {
    const auto [it, added] = indexOf.emplace(keyOf(leaf), static_cast<uint32_t>(first.size()));
    if (added) first.push_back(&leaf);
    out.imageOfLeaf.push_back(it->second);
  }
  if (first.size() > maxImages) {
    throwInputError(
        "the tree's leaves use {} distinct (texture, uv rectangle) pairs; the leaf images hold at "
        "most {}",
        first.size(), maxImages);
  }
  out.layers.resize(first.size() * 2);
  constexpr int kSupersample = 4;
  tbb::parallel_for(size_t(0), out.layers.size(), [&](size_t layer) {
    const Leaf& leaf = *first[layer / 2];
    const bool back = layer % 2 == 1;
    const glm::ivec2 texSize = sampler.size(leaf.texture);
    const glm::vec2 span = glm::abs(leaf.uvMax - leaf.uvMin);
    const float footprint =
        std::max(texSize.x * span.x, texSize.y * span.y) / float(size * kSupersample);
    out.layers[layer] = renderCoverageImage(size, kSupersample, [&](glm::vec2 unit) {
      return sampler.sample(leaf.texture, back, leaf.uvMin + unit * (leaf.uvMax - leaf.uvMin),
                            footprint);
    });
  });
  return out;
}

}  // namespace canopy
