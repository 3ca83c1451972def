#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "common/image.h"
#include "common/tree.h"
#include "methods/common/billboard_cloud.h"
#include "methods/common/leaf_orientations.h"

namespace canopy {

// How big a leaf's point sprite is (García et al. 2007 §4.2).
enum class SpriteRule {
  kPaper,   // §4.2: leaf_pixels = area(2D box of the projected leaf) · billboard_pixels /
            // area(billboard); a square of that area, the leaf image scaled into it
  kBounds,  // the square that contains the projected leaf at any rotation (side = leaf length)
};
SpriteRule parseSpriteRule(const std::string& name);  // "paper" | "bounds"

// One entry of a Lists Texture list: a leaf fragment overlapping a cell.
struct LayerEntry {
  glm::vec2 position{
      0.0f};                // leaf centre on the billboard plane (units of length, from its centre)
  float size = 0.0f;        // side of the square the leaf image spans (the sprite)
  uint32_t image = 0;       // oriented leaf image seen from the billboard's front
  uint32_t leaf = 0;        // index into Tree::leaves
  float depth = 0.0f;       // along the billboard normal; lists are sorted by it, largest first
  glm::vec4 ambient{1.0f};  // ambient occlusion at the sprite's corners (−,−) (+,−) (+,+) (−,+)
  // Which way the leaf's normal leans across its axis (+1/−1): the orientation bins hold the
  // axis angle and |n·n_billboard| but not this sign, which lit shading needs (§5.2: "a
  // correction for the billboard plane normal could also be stored in the entries").
  int roll = 1;
};

// A billboard's Hash Texture (a grid of cells, each naming a list or empty) and its lists,
// stored consecutively as in the Lists Texture.
struct LayeredBillboard {
  glm::ivec2 cells{1, 1};
  glm::vec2 cellSize{1.0f};          // on the billboard plane
  std::vector<uint32_t> listStart;   // per cell, row-major: first entry in `entries`
  std::vector<uint32_t> listLength;  // per cell: 0 when the cell is empty
  std::vector<LayerEntry> entries;
  uint32_t droppedEntries = 0;  // fragments beyond maxLayers (kept: the front-most)
};

struct LayeringParams {
  int hashResolution = 32;  // cells along the billboard's longer side
  int maxLayers = 16;       // longest list kept (front-most fragments first)
  SpriteRule sprite = SpriteRule::kPaper;
  OrientationBins bins;
};

// The sprite square of a leaf on a billboard: centre and side, as `rule` defines it.
LayerEntry leafSprite(const Leaf& leaf, const Billboard& billboard, SpriteRule rule);

// Builds the hash grid and the lists: every leaf of the billboard is a point sprite listed in
// each cell its square overlaps (with positive area), lists sorted front to back along the
// billboard normal. Exact CPU construction of what the paper obtains by depth peeling.
// `cornerOcclusion` (per leaf, at its four corners; may be null) fills each entry's `ambient` by
// the least-squares extrapolation of §5.2 to the sprite's corners.
LayeredBillboard buildLayeredBillboard(const Tree& tree, const Billboard& billboard,
                                       const LayeringParams& params,
                                       const std::vector<glm::vec4>* cornerOcclusion = nullptr);

// Walks the list of the cell under `point` (billboard plane coordinates) from the end facing the
// viewer, as the fragment shader does, over at most `budget` entries (< 0: all); returns the
// first opaque texel (alpha >= 0.5) of the entries' images, or nothing. `images` are the oriented
// leaf images; seen from the back, each entry's image is its other side.
struct LayerHit {
  uint32_t entry = 0;     // index into LayeredBillboard::entries
  glm::vec4 color{0.0f};  // straight sRGB 0..1 of the nearest texel of the image
};
std::optional<LayerHit> walkLayers(const LayeredBillboard& layered, const Billboard& billboard,
                                   const std::vector<ImageRgba8>& images,
                                   const OrientationBins& bins, glm::vec2 point, bool fromFront,
                                   int budget = -1);

// The image index of the same orientation seen from the other side of the billboard.
uint32_t otherSideImage(uint32_t image, const OrientationBins& bins);

}  // namespace canopy
