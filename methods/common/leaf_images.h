#pragma once

#include <cstdint>
#include <vector>

#include "common/image.h"
#include "common/tree.h"
#include "methods/common/leaf_capture.h"

namespace canopy {

// The Leaves Texture when each leaf is drawn through its own frame (multi-layer indirect
// texturing): one image per distinct (leaf texture, uv rectangle) the tree's leaves use, front
// and back, each the rectangle resampled to size × size texels (4×4 samples a texel, alpha the
// covered share). Most trees need one image per leaf texture.
struct LeafImages {
  std::vector<ImageRgba8> layers;     // image i: its front at layer 2i, its back at 2i + 1
  std::vector<uint32_t> imageOfLeaf;  // per tree leaf
  size_t count() const { return layers.size() / 2; }
};

// Throws InputError when the leaves use more than `maxImages` distinct rectangles.
LeafImages buildLeafImages(const Tree& tree, const LeafImageSampler& sampler, int size,
                           size_t maxImages);

}  // namespace canopy
