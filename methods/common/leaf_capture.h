#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "common/image.h"
#include "common/tree.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// An sRGB RGBA image as a linear float mip pyramid (straight alpha; box-filtered levels with
// colour weighted by alpha, so transparent texels do not darken edges), sampled on the CPU.
class LinearMipPyramid {
 public:
  explicit LinearMipPyramid(const ImageRgba8& image);
  // Bilinear sample at uv (Canopy convention, clamped) from the level matching `footprint`, the
  // base-level texels one sample covers; rgb linear, a straight alpha.
  glm::vec4 sample(glm::vec2 uv, float footprint) const;
  glm::ivec2 size() const { return {mLevels[0].width, mLevels[0].height}; }

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<glm::vec4> texels;
  };
  std::vector<Level> mLevels;
};

// Leaf images as linear float mip pyramids, sampled on the CPU by every bake that projects
// leaves (billboard textures, leaf images at quantized orientations).
class LeafImageSampler {
 public:
  explicit LeafImageSampler(const Tree& tree);
  // LinearMipPyramid::sample of the texture's front or back image.
  glm::vec4 sample(uint32_t texture, bool back, glm::vec2 uv, float footprint) const;
  glm::ivec2 size(uint32_t texture) const;

 private:
  std::vector<LinearMipPyramid> mPyramids;  // [texture * 2 + back]
};

// The wood's albedo (material base colour × texture, linear) on the CPU, for bakes that capture
// wood into images.
class WoodColorSampler {
 public:
  explicit WoodColorSampler(const Tree& tree);
  // The colour at barycentric coordinates `weights` of wood triangle `triangle`, its texture
  // filtered over `sampleSize` world units (the capture's sample spacing over the triangle).
  glm::vec3 sample(uint32_t triangle, const glm::vec3& weights, float sampleSize) const;

 private:
  const WoodMesh& mWood;
  std::vector<glm::vec3> mBaseColors;  // linear, per material
  std::vector<int> mTextures;          // per material: index into mPyramids, -1 for none
  std::vector<LinearMipPyramid> mPyramids;
};

// An orthographic capture's samples over a billboard rectangle, row-major, `width` × `height`:
// each sample's nearness to the camera (height along the camera's side of the normal; −infinity
// where nothing was seen) and linear colour; `wood`, when set, marks the samples wood won.
struct OrthographicSamples {
  int width = 0, height = 0;
  std::vector<float>& nearness;
  std::vector<glm::vec3>& color;
  std::vector<bool>* wood = nullptr;
};

// Draws the wood triangles `triangles` (opaque, their albedo) into `samples` of `billboard`'s
// rectangle seen from its +normal side (−normal when `fromBack`), keeping the nearer of what the
// samples hold and the wood.
void rasterizeWoodOrthographic(const Tree& tree, const WoodColorSampler& wood,
                               const std::vector<uint32_t>& triangles, const Billboard& billboard,
                               bool fromBack, OrthographicSamples& samples);

// Writes a texel from `samples` samples of which `covered` hit a leaf, `linearSum` their summed
// linear colour: RGB the sRGB-encoded mean (left as is when nothing is covered), alpha the
// coverage.
void writeCoverageTexel(uint8_t* out, const glm::vec3& linearSum, int covered, int samples);

// A size × size image of a leaf: `sample(unit)` gives the leaf's texel seen at a point of the
// unit square (alpha < 0.5: not covered), taken supersample² times a texel. Colour: the linear
// mean of the covered samples; alpha: their share; transparent texels get their covered
// neighbours' colour (4 texels), so filtering does not pull in black.
ImageRgba8 renderCoverageImage(int size, int supersample,
                               const std::function<glm::vec4(glm::vec2 unit)>& sample);

// What an orthographic camera on the +normal side of `billboard` (the −normal side when
// `fromBack`) sees of `leaves` (and only them), over the billboard rectangle, at width × height
// texels with supersample² samples per texel; each leaf alpha-tested at 0.5, front or back image
// by the side it turns to the camera. Texel (x, y) is the same plane point from either side, so
// a back capture is sampled with the front's uv. Texel colour: the linear mean of covered
// samples, sRGB-encoded; alpha: the covered fraction. With `wood`, the wood triangles
// `woodTriangles` are seen too (opaque, their albedo), leaves and wood hiding one another by depth.
ImageRgba8 captureLeavesOrthographic(const Tree& tree, const LeafImageSampler& sampler,
                                     const std::vector<uint32_t>& leaves,
                                     const Billboard& billboard, int width, int height,
                                     int supersample, bool fromBack = false,
                                     const WoodColorSampler* wood = nullptr,
                                     const std::vector<uint32_t>& woodTriangles = {});

// Positions of rectangles in an atlas: shelves sorted by height, each rectangle inside a slot
// with `padding` texels on every side, slots aligned to `alignment` texels (so the first
// log2(alignment) mip levels of different rectangles never share a texel); a rectangle smaller
// than that gets the alignment (and at most half of it as padding) of its longer side, as past
// those levels it is under a texel.
struct AtlasLayout {
  int width = 0;
  int height = 0;
  std::vector<glm::ivec2> origins;  // of each rectangle's first texel (inside its padding)
};
AtlasLayout packAtlas(const std::vector<glm::ivec2>& sizes, int padding, int alignment);

// Images packed into one atlas (packAtlas), transparent texels dilated by `alignment` texels.
struct ImageAtlas {
  ImageRgba8 image;
  AtlasLayout layout;
  std::vector<glm::ivec2> sizes;
  // Atlas uv of corner i (CCW from (−,−)) of image `index`.
  glm::vec2 cornerUv(size_t index, int corner) const;
};
ImageAtlas composeAtlas(const std::vector<ImageRgba8>& images, int padding, int alignment);

// Each billboard's leaves captured orthographically (captureLeavesOrthographic) at sizes[i]
// texels, from its front and, with `backToo`, its back, packed into one atlas per side with the
// same layout (a back capture is sampled with the front's uv). `woodPerBillboard`, when given,
// names per billboard the wood triangles its images hold (`wood` samples their colour).
struct TwoSidedAtlas {
  ImageAtlas front;
  ImageRgba8 back;  // empty without backToo
};
TwoSidedAtlas captureTwoSidedAtlas(
    const Tree& tree, const LeafImageSampler& sampler,
    const std::vector<const Billboard*>& billboards, const std::vector<glm::ivec2>& sizes,
    int supersample, bool backToo, int padding, int alignment,
    const WoodColorSampler* wood = nullptr,
    const std::vector<std::vector<uint32_t>>* woodPerBillboard = nullptr);

// Gives fully transparent texels the colour of their nearest covered neighbours (up to
// `passes` texels away), so bilinear and mip filtering near leaf edges do not pull in black.
void dilateTransparentColors(ImageRgba8& image, int passes);

}  // namespace canopy
