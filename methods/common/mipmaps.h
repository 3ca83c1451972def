#pragma once

#include <vector>

#include "common/gl/device.h"
#include "common/image.h"
#include "methods/common/dxt.h"

namespace canopy {

// A full mip chain (level 0 = `base`) for alpha-tested textures. Colour is averaged in linear
// space weighted by alpha; each level's alpha is then scaled so that the fraction of texels
// passing the alpha test matches level 0 (Castaño's coverage-preserving mipmaps). Plain box
// filtering lets averaged alpha of sparse foliage fall under the threshold, and far billboards
// vanish.
std::vector<ImageRgba8> buildCoveragePreservingMips(const ImageRgba8& base,
                                                    float alphaThreshold = 0.5f);

}  // namespace canopy

namespace canopy {

// A 2D sRGB texture with the chain above (or level 0 only when !mipmaps), linear filtering,
// every level block-compressed unless `compression` is kNone.
gl::Texture uploadAlphaTestedTexture(gl::Device& device, const ImageRgba8& image, bool mipmaps,
                                     const char* label,
                                     Compression compression = Compression::kNone);

}  // namespace canopy
