#include "methods/common/ambient_occlusion.h"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "common/random.h"

namespace canopy {
namespace {

// The intersect context carries which leaf a ray leaves from and the tree, for the filter.
struct OcclusionContext {
  RTCIntersectContext context;  // first member: Embree passes a pointer to it
  const Tree* tree = nullptr;
  uint32_t sourceLeaf = UINT32_MAX;
};

// Leaves are two triangles each (primID / 2 is the leaf): reject hits on the ray's own leaf and on
// transparent texels of the leaf texture.
void leafOcclusionFilter(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const OcclusionContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned primitive = RTCHitN_primID(args->hit, args->N, i);
    const uint32_t leafIndex = primitive / 2;
    if (leafIndex == context->sourceLeaf) {
      args->valid[i] = 0;
      continue;
    }
    const Leaf& leaf = context->tree->leaves[leafIndex];
    // Triangles (0,1,2) and (0,2,3) of the corners; barycentrics → corner-space unit coordinates.
    const float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
    static const glm::vec2 kUnit[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const glm::vec2 unit = primitive % 2 == 0
                               ? kUnit[0] * (1 - u - v) + kUnit[1] * u + kUnit[2] * v
                               : kUnit[0] * (1 - u - v) + kUnit[2] * u + kUnit[3] * v;
    const glm::vec2 uv = leaf.uvMin + unit * (leaf.uvMax - leaf.uvMin);
    const ImageRgba8& image = context->tree->leafTextures[leaf.texture].front;
    const int x = std::clamp(static_cast<int>(uv.x * image.width), 0, image.width - 1);
    const int y = std::clamp(static_cast<int>(uv.y * image.height), 0, image.height - 1);
    if (image.at(x, y)[3] < 128) args->valid[i] = 0;
  }
}

class EmbreeScene {
 public:
  explicit EmbreeScene(const Tree& tree) {
    mDevice = rtcNewDevice(nullptr);
    if (!mDevice) throw std::runtime_error("Embree: cannot create a device");
    mScene = rtcNewScene(mDevice);
    if (!tree.wood.positions.empty()) {
      RTCGeometry wood = rtcNewGeometry(mDevice, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vertices = static_cast<float*>(
          rtcSetNewGeometryBuffer(wood, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                  3 * sizeof(float), tree.wood.positions.size()));
      for (size_t i = 0; i < tree.wood.positions.size(); ++i) {
        vertices[i * 3 + 0] = tree.wood.positions[i].x;
        vertices[i * 3 + 1] = tree.wood.positions[i].y;
        vertices[i * 3 + 2] = tree.wood.positions[i].z;
      }
      auto* indices = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(wood, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(unsigned), tree.wood.triangleCount()));
      std::copy(tree.wood.indices.begin(), tree.wood.indices.end(), indices);
      rtcCommitGeometry(wood);
      rtcAttachGeometry(mScene, wood);
      rtcReleaseGeometry(wood);
    }
    RTCGeometry leaves = rtcNewGeometry(mDevice, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(leaves, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), tree.leaves.size() * 4));
    auto* indices = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(leaves, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), tree.leaves.size() * 2));
    for (size_t l = 0; l < tree.leaves.size(); ++l) {
      for (int c = 0; c < 4; ++c) {
        const glm::vec3 p = tree.leaves[l].corner(c);
        vertices[(l * 4 + c) * 3 + 0] = p.x;
        vertices[(l * 4 + c) * 3 + 1] = p.y;
        vertices[(l * 4 + c) * 3 + 2] = p.z;
      }
      const unsigned b = static_cast<unsigned>(l * 4);
      const unsigned quad[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
      std::copy(quad, quad + 6, indices + l * 6);
    }
    rtcSetGeometryOccludedFilterFunction(leaves, leafOcclusionFilter);
    rtcCommitGeometry(leaves);
    mLeafGeometry = rtcAttachGeometry(mScene, leaves);
    rtcReleaseGeometry(leaves);
    rtcCommitScene(mScene);
  }
  ~EmbreeScene() {
    rtcReleaseScene(mScene);
    rtcReleaseDevice(mDevice);
  }
  RTCScene scene() const { return mScene; }

 private:
  RTCDevice mDevice = nullptr;
  RTCScene mScene = nullptr;
  unsigned mLeafGeometry = 0;
};

}  // namespace

std::vector<glm::vec4> computeLeafCornerOcclusion(const Tree& tree, int rays, uint64_t seed) {
  const EmbreeScene embree(tree);
  const float epsilon = 1e-4f * tree.boundingSphereRadius();
  std::vector<glm::vec4> result(tree.leaves.size());
  tbb::parallel_for(size_t(0), tree.leaves.size(), [&](size_t l) {
    OcclusionContext context;
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

glm::vec4 fitCornerValues(const std::vector<glm::vec2>& points, const std::vector<float>& values,
                          glm::vec2 spriteCenter, float spriteSide) {
  const size_t n = points.size();
  Eigen::MatrixXd a(n, 4);
  Eigen::VectorXd b(n);
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec2 unit = (points[i] - spriteCenter) / spriteSide + 0.5f;
    const double s = unit.x, t = unit.y;
    a.row(i) << (1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t;
    b(i) = values[i];
    mean += values[i];
  }
  mean /= double(std::max<size_t>(n, 1));
  // Least squares on the deviation from the mean; the complete orthogonal decomposition gives the
  // minimum-norm solution when the points do not determine all four corners.
  const Eigen::VectorXd deviation =
      a.completeOrthogonalDecomposition().solve(b - Eigen::VectorXd::Constant(n, mean));
  return glm::vec4(float(mean + deviation(0)), float(mean + deviation(1)),
                   float(mean + deviation(2)), float(mean + deviation(3)));
}

float interpolateCorners(const glm::vec4& corners, glm::vec2 unit) {
  return corners[0] * (1 - unit.x) * (1 - unit.y) + corners[1] * unit.x * (1 - unit.y) +
         corners[2] * unit.x * unit.y + corners[3] * (1 - unit.x) * unit.y;
}

}  // namespace canopy
