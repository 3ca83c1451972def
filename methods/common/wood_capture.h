#pragma once

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/tree.h"
#include "methods/common/billboard_cloud.h"
#include "methods/common/wood_levels.h"

namespace canopy {

// Which wood triangles a cloud's images can hold, and in which billboard. The candidates for a
// triangle are the billboards whose rectangle contains its three corners' projections with every
// corner within `maxDistance` of the plane (its flattening error, world units); it goes to the
// candidate its facet faces most squarely (so, as for leaves, the facet keeps its projected area
// from every view), the nearest among equals. One list of triangle indices per billboard; a
// triangle in none stays geometry.
std::vector<std::vector<uint32_t>> assignWoodToBillboards(const WoodMesh& wood,
                                                          const std::vector<Billboard>& billboards,
                                                          float maxDistance);

// The connected parts of the wood (WoodMesh::vertexParts) per triangle: triangles that share a
// corner position are in one part, numbered in the order of the parts' first triangles.
std::vector<uint32_t> woodParts(const WoodMesh& wood);

// As assignWoodToBillboards, a part at a time: a part goes whole to the billboard nearest it
// among those whose rectangle contains every corner of it within `maxDistance` of the plane, or
// stays geometry whole.
// Flattened into one plane a branch keeps its outline from every view, where facets spread over
// planes at different depths scatter (docs/METHODS.md).
std::vector<std::vector<uint32_t>> assignWoodPartsToBillboards(
    const WoodMesh& wood, const std::vector<uint32_t>& parts,
    const std::vector<Billboard>& billboards, float maxDistance);

// The wood a cloud family's images hold. Clouds from `firstImageCloud` on are drawn as images
// only; cloud c at most at `largestPixels[c - firstImageCloud]` output pixels of projected
// radius, so it may flatten wood by `capturePixels` × radius / largest world units. A triangle
// is captured when every image cloud holds it within its bound (assignWoodToBillboards): the
// images then hold exactly the wood that trees drawn with them do not draw as geometry.
// `farCapturePixels` (0: none) gives the last image cloud a bound of its own instead: it holds
// every triangle within that many of its pixels, and trees drawn with it draw only the rest (a
// residual chain of their own), while the clouds before it keep the set above. `wholeParts`:
// assign whole parts (assignWoodPartsToBillboards) instead of triangles.
struct WoodInImages {
  std::vector<CapturedWood> captured;               // per residual chain; empty: none
  std::vector<std::vector<uint32_t>> perBillboard;  // over every cloud's billboards in order
  nlohmann::json report;  // triangles captured and each image cloud's plane-distance bound
};
WoodInImages captureWoodInImages(const Tree& tree, const std::vector<BillboardCloud>& clouds,
                                 size_t firstImageCloud, const std::vector<float>& largestPixels,
                                 float capturePixels, float farCapturePixels = 0.0f,
                                 bool wholeParts = false);

// A method's `wood_capture_px` / `wood_capture_far_px` as they take effect, written back in
// place: both 0 without coarse images to hold wood (`lod` off) or wood to hold (`wood` off);
// otherwise a far bound below the near one is an input error naming `method`'s parameter.
void resolveWoodCapture(const char* method, bool lod, bool wood, float& capturePixels,
                        float& farCapturePixels);

}  // namespace canopy
