#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "common/image.h"
#include "common/tree.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

class WoodColorSampler;  // methods/common/leaf_capture.h

// One leaf as its billboard sees it (García et al. 2007 §4.2: "each leaf has an associated
// vector that represents its position in local billboard coordinates"), in the billboard's frame
// (axisU, axisV, normal). The paper keeps a position, a scale and an orientation index into leaf
// images at quantized orientations; a record keeps the leaf's own frame instead, so the shader
// maps a point of the plane into the leaf's (s, t) and draws every flat leaf with its true
// outline, size and side.
struct LeafRecord {
  glm::vec2 center{0.0f};   // on the plane, from the billboard centre
  float height = 0.0f;      // of the leaf centre along the billboard normal
  glm::vec3 axisU{0.0f};    // the leaf's axisU · halfExtents.x, in the billboard frame
  glm::vec3 axisV{0.0f};    // the leaf's axisV · halfExtents.y, in the billboard frame
  uint32_t image = 0;       // leaf image (front layer 2·image, back 2·image + 1)
  uint32_t leaf = 0;        // index into Tree::leaves
  glm::vec4 ambient{1.0f};  // ambient occlusion at the leaf corners (−,−) (+,−) (+,+) (−,+)

  // The leaf point seen through plane point `p` along a ray whose in-plane slope is `slope`
  // (d_t / d_n of the ray direction d; zero: along the normal), as leaf coordinates (s, t), each
  // in [−1, 1] on the leaf. Nothing when the ray runs along the leaf.
  std::optional<glm::vec2> locate(glm::vec2 p, glm::vec2 slope) const;
  // Height along the billboard normal of leaf point (s, t).
  float heightAt(glm::vec2 st) const { return height + st.x * axisU.z + st.y * axisV.z; }
  // The front of the leaf (axisU × axisV, the winding the reference draws) faces `towardsViewer`.
  bool frontFaces(const glm::vec3& towardsViewer) const;
  // The largest distance of a corner from the plane.
  float maxCornerHeight() const;
  // The plane rectangle the leaf can appear in for rays with |slope| <= maxSlope per axis.
  void footprint(float maxSlope, glm::vec2& lo, glm::vec2& hi) const;
};

// A billboard's Hash Texture (a grid of cells, each naming a list or empty), its lists (record
// indices, front to back along the normal) and its records, as in the Lists Texture.
struct LayeredBillboard {
  glm::vec2 halfExtents{0.0f};  // of the drawn rectangle: the billboard's, grown for parallax
  glm::ivec2 cells{1, 1};
  glm::vec2 cellSize{1.0f};          // on the billboard plane
  std::vector<LeafRecord> records;   // one per leaf of the billboard, in its order
  std::vector<uint32_t> listStart;   // per cell, row-major: first entry in `entries`
  std::vector<uint32_t> listLength;  // per cell: 0 when the cell is empty
  std::vector<uint32_t> entries;     // record indices, each list front (largest height) first
  uint32_t droppedEntries = 0;       // fragments beyond maxLayers (kept: the front-most)
};

struct LayeringParams {
  float cellSize = 1.0f;  // side of a hash cell on the plane (world units)
  int maxLayers = 64;     // longest list kept (front-most fragments first)
  // Parallax: rays up to this in-plane slope (tan of the angle from the normal) find every leaf
  // they cross; the rectangle and the cells grow by each leaf's corner heights times it.
  // 0: leaves are looked up along the normal only (the paper).
  float maxSlope = 0.0f;
};

// The record of `leaf` on `billboard`; `image` names its leaf image.
LeafRecord makeLeafRecord(const Leaf& leaf, const Billboard& billboard, uint32_t image);

// Builds the records, the hash grid and the lists: every leaf is listed in each cell its
// footprint overlaps with positive area, lists sorted front to back along the billboard normal
// (ties by leaf index). Exact CPU construction of what the paper obtains by depth peeling.
// `imageOfLeaf` gives each tree leaf's image; `cornerOcclusion` (per leaf, may be null) the
// ambient occlusion at its corners.
LayeredBillboard buildLayeredBillboard(const Tree& tree, const Billboard& billboard,
                                       const std::vector<uint32_t>& imageOfLeaf,
                                       const LayeringParams& params,
                                       const std::vector<glm::vec4>* cornerOcclusion = nullptr);

// Walks the list of the cell under `point` (billboard plane coordinates) from the end facing the
// viewer along the normal, as the fragment shader does for a ray along it, over at most `budget`
// entries (< 0: all); returns the first opaque texel (alpha >= 0.5, nearest texel) of the leaves'
// images, each leaf showing the side it turns to the viewer. `leafLayers` are the leaf images,
// front and back (layer 2·image + side).
struct LayerHit {
  uint32_t record = 0;    // index into LayeredBillboard::records
  glm::vec2 st{0.0f};     // leaf coordinates of the hit
  glm::vec4 color{0.0f};  // straight sRGB 0..1
};
std::optional<LayerHit> walkLayers(const LayeredBillboard& layered,
                                   const std::vector<ImageRgba8>& leafLayers, glm::vec2 point,
                                   bool fromFront, int budget = -1);

// Wood a low-resolution texture holds (wood_capture_px): the triangles, the billboard's frame
// with the layered rectangle's half extents, and the wood's colours.
struct LayeredWood {
  const Tree& tree;
  const WoodColorSampler& colors;
  const std::vector<uint32_t>& triangles;
  Billboard billboard;
};

// The low-resolution texture of §5.1: what the full walk shows of the layered billboard from its
// front (or back) side, `texelsPerCell` texels per hash cell side, 4×4 samples a texel: colour
// (linear mean, sRGB-encoded) and coverage. With `wood`, its triangles are seen too, leaves and
// wood hiding one another by height. `occlusion` (optional) gets the mean ambient occlusion of
// the leaves hit (1 where nothing or wood is), its alpha the coverage.
ImageRgba8 captureLayered(const LayeredBillboard& layered,
                          const std::vector<ImageRgba8>& leafLayers, int texelsPerCell,
                          bool fromFront, ImageRgba8* occlusion = nullptr,
                          const LayeredWood* wood = nullptr);

}  // namespace canopy
