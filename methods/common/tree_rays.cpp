#include "methods/common/tree_rays.h"

#include <algorithm>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace canopy {
namespace {

// Whether the leaf texel under a hit is part of the blade: the image the ray sees (front when it
// arrives against the normal), nearest texel, alpha >= 128 (the alpha test every method uses).
bool leafTexelOpaque(const Tree& tree, unsigned primitive, float u, float v, bool back) {
  const Leaf& leaf = tree.leaves[primitive / 2];
  const glm::vec2 uv =
      leaf.uvMin + leafUnitCoordinates(primitive, u, v) * (leaf.uvMax - leaf.uvMin);
  const LeafTexture& texture = tree.leafTextures[leaf.texture];
  const ImageRgba8& image = back ? texture.back : texture.front;
  const int x = std::clamp(static_cast<int>(uv.x * image.width), 0, image.width - 1);
  const int y = std::clamp(static_cast<int>(uv.y * image.height), 0, image.height - 1);
  return image.at(x, y)[3] >= 128;
}

// Occlusion rays (ambient occlusion): the front image's blade, never the ray's own leaf.
void leafOcclusionFilter(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const TreeRayContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned primitive = RTCHitN_primID(args->hit, args->N, i);
    if (primitive / 2 == context->sourceLeaf ||
        !leafTexelOpaque(*context->tree, primitive, RTCHitN_u(args->hit, args->N, i),
                         RTCHitN_v(args->hit, args->N, i), false))
      args->valid[i] = 0;
  }
}

// Camera rays (captures): the blade of the image on the side the ray sees.
void leafIntersectFilter(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const TreeRayContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned primitive = RTCHitN_primID(args->hit, args->N, i);
    const Leaf& leaf = context->tree->leaves[primitive / 2];
    const glm::vec3 direction(RTCRayN_dir_x(args->ray, args->N, i),
                              RTCRayN_dir_y(args->ray, args->N, i),
                              RTCRayN_dir_z(args->ray, args->N, i));
    const bool back = glm::dot(direction, leaf.normal) > 0.0f;
    if (!leafTexelOpaque(*context->tree, primitive, RTCHitN_u(args->hit, args->N, i),
                         RTCHitN_v(args->hit, args->N, i), back))
      args->valid[i] = 0;
  }
}

}  // namespace

glm::vec2 leafUnitCoordinates(unsigned primitive, float u, float v) {
  // Corners (0,0) (1,0) (1,1) (0,1); barycentrics weight the triangle's second and third corner.
  return primitive % 2 == 0 ? glm::vec2(u + v, v) : glm::vec2(u, u + v);
}

TreeRayScene::TreeRayScene(const Tree& tree) {
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
    mWoodGeometry = rtcAttachGeometry(mScene, wood);
    rtcReleaseGeometry(wood);
  }
  if (!tree.leaves.empty()) {
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
    rtcSetGeometryIntersectFilterFunction(leaves, leafIntersectFilter);
    rtcCommitGeometry(leaves);
    mLeafGeometry = rtcAttachGeometry(mScene, leaves);
    rtcReleaseGeometry(leaves);
  }
  rtcCommitScene(mScene);
}

TreeRayScene::~TreeRayScene() {
  rtcReleaseScene(mScene);
  rtcReleaseDevice(mDevice);
}

}  // namespace canopy
