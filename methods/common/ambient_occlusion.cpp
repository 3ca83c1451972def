#include "methods/common/ambient_occlusion.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "common/random.h"
#include "methods/common/tree_rays.h"

namespace canopy {

std::vector<glm::vec4> computeLeafCornerOcclusion(const Tree& tree, int rays, uint64_t seed) {
  const TreeRayScene embree(tree);
  const float epsilon = 1e-4f * tree.boundingSphereRadius();
  std::vector<glm::vec4> result(tree.leaves.size());
  tbb::parallel_for(size_t(0), tree.leaves.size(), [&](size_t l) {
    TreeRayContext context;
    rtcInitIntersectContext(&context.context);
    context.tree = &tree;
    context.sourceLeaf = static_cast<uint32_t>(l);
    const Leaf& leaf = tree.leaves[l];
    for (int c = 0; c < 4; ++c) {
      Random random(seed ^ (uint64_t(l) * 4 + uint64_t(c)) * 0x9e3779b97f4a7c15ULL,
                    0xda3e39cb94b95bdbULL);
      // Corners pulled slightly inside, so rays do not start on a neighbouring leaf's edge.
      const glm::vec3 origin = leaf.corner(c) + (leaf.center - leaf.corner(c)) * 0.02f;
      int open = 0;
      for (int r = 0; r < rays; ++r) {
        const float z = random.uniform(-1.0f, 1.0f), phi = random.uniform(0.0f, 6.2831853f);
        const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
        RTCRay ray{};
        ray.org_x = origin.x;
        ray.org_y = origin.y;
        ray.org_z = origin.z;
        ray.dir_x = s * std::cos(phi);
        ray.dir_y = s * std::sin(phi);
        ray.dir_z = z;
        ray.tnear = epsilon;
        ray.tfar = std::numeric_limits<float>::infinity();
        ray.mask = 0xffffffffu;
        rtcOccluded1(embree.scene(), &context.context, &ray);
        open += ray.tfar >= 0.0f ? 1 : 0;  // Embree sets tfar to −inf on occlusion
      }
      result[l][c] = float(open) / float(std::max(rays, 1));
    }
  });
  return result;
}

float interpolateCorners(const glm::vec4& corners, glm::vec2 unit) {
  return corners[0] * (1 - unit.x) * (1 - unit.y) + corners[1] * unit.x * (1 - unit.y) +
         corners[2] * unit.x * unit.y + corners[3] * (1 - unit.x) * unit.y;
}

}  // namespace canopy
