#pragma once

#include <cstdint>
#include <vector>

#include "common/image.h"
#include "common/tree.h"
#include "methods/common/billboard_cloud.h"
#include "methods/common/leaf_capture.h"

namespace canopy {

// The Leaves Texture of indirect texturing (García et al. 2005, 2007 §3): leaf images at
// quantized orientations relative to a billboard plane. A leaf projected on a billboard is
// described by the in-plane angle of its axis (rotation) and its foreshortening |n·n_leaf|
// (tilt), and by the side it turns to the billboard's front (front or back image).
struct OrientationBins {
  int rotations = 8;  // in-plane angle steps over 360°
  int tilts = 2;      // foreshortening steps over (0, 1]; the width of bin j is (j + 1) / tilts

  // As method parameters (config keys "rotations", "tilts").
  template <class Visitor>
  void visit(Visitor& v) {
    v("rotations", rotations, 1, 64, "Leaves Texture: in-plane angle steps over 360°");
    v("tilts", tilts, 1, 8, "Leaves Texture: foreshortening steps over (0, 1]");
  }
};

// Image index of a leaf on a billboard: ((texture·2 + back)·tilts + tilt)·rotations + rotation.
uint32_t orientedImageIndex(const Leaf& leaf, const Billboard& billboard,
                            const OrientationBins& bins);
uint32_t orientedImageCount(size_t leafTextures, const OrientationBins& bins);

// Every oriented image, square, `size` texels a side. The square spans the leaf's length
// (2·max(half extents)) centred on the leaf centre, so a leaf at any rotation fits inside.
// Supersampled 4×4, alpha = coverage; uv rectangle and aspect from the first leaf of each texture.
std::vector<ImageRgba8> buildOrientedLeafImages(const Tree& tree, const LeafImageSampler& sampler,
                                                const OrientationBins& bins, int size);

}  // namespace canopy
