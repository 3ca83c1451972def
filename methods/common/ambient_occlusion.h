#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "common/tree.h"

namespace canopy {

// Ambient occlusion of the polygonal tree (García et al. 2007 §5.2 precompute it on the original
// tree): at each leaf corner, the fraction of `rays` directions over the sphere (both sides of a
// two-sided leaf) that escape the tree. Rays are cast with Embree against the wood and the leaves,
// leaves alpha-tested through their textures; a leaf never occludes itself. Deterministic in
// `seed` whatever the thread count (each corner has its own random stream).
std::vector<glm::vec4> computeLeafCornerOcclusion(const Tree& tree, int rays, uint64_t seed);

// Bilinear interpolation of corner values (−,−) (+,−) (+,+) (−,+) at unit coordinates in [0, 1]².
float interpolateCorners(const glm::vec4& corners, glm::vec2 unit);

}  // namespace canopy
