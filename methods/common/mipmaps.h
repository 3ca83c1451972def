#pragma once

#include <vector>

#include "common/gl/device.h"
#include "common/image.h"
#include "methods/common/dxt.h"

namespace canopy {

// The share of an image's area an alpha test at 0.5 keeps once the texture unit has filtered
// it: the bilinear reconstruction of alpha sampled 2×2 times per texel (`binary`: the alpha first
// cut at 0.5, as BC1 stores it, then filtered).
double alphaTestedArea(const ImageRgba8& image, bool binary);

// What the alpha-tested area of every mip level is matched to.
enum class CoverageTarget {
  // The covered area, the mean alpha of level 0; level 0 is scaled too. For images of single
  // leaves or planes of leaves, each drawn alone and tested alone.
  kCoveredArea,
  // The area level 0 passes as captured; level 0 is kept. For whole-tree frames that the shader
  // blends with other frames before its test, where scaling level 0 thickens the blend (measured
  // on octahedral: 17.6 -> 17.2 dB at 1.5 radii, 20.3 -> 19.4 at 12).
  kLevelZeroTest,
};

// A full mip chain (level 0 = `base`, or `base` alone when !mipmaps) for alpha-tested textures
// whose alpha is coverage. Colour is averaged in linear space weighted by alpha. Every level's
// alpha is then scaled so that the area the alpha test keeps after bilinear filtering (as
// `compression` stores alpha: cut at 0.5 for BC1) equals `target`'s area. Plain box filtering lets
// the averaged alpha of sparse foliage fall under the threshold and distant billboards vanish;
// matching the count of passing texels instead of the filtered area still loses the thin parts a
// bilinear threshold cuts off (and made BC1, whose 1-bit alpha rounds them up, look better than no
// compression).
std::vector<ImageRgba8> buildCoveragePreservingMips(
    const ImageRgba8& base, Compression compression = Compression::kNone, bool mipmaps = true,
    CoverageTarget target = CoverageTarget::kCoveredArea);

// A 2D sRGB texture with the chain above, linear filtering, every level block-compressed unless
// `compression` is kNone.
gl::Texture uploadAlphaTestedTexture(gl::Device& device, const ImageRgba8& image, bool mipmaps,
                                     const char* label, Compression compression,
                                     CoverageTarget target);

// The same for images of one size as the layers of one sRGB 2D array texture.
gl::Texture uploadAlphaTestedArray(gl::Device& device, const std::vector<ImageRgba8>& layers,
                                   bool mipmaps, const char* label,
                                   Compression compression = Compression::kNone);

}  // namespace canopy
