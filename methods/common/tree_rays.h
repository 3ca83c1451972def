#pragma once

#include <embree3/rtcore.h>

#include <cstdint>

#include <glm/vec2.hpp>

#include "common/tree.h"

namespace canopy {

// The tree as an Embree scene: the wood mesh (geometry woodGeometry(), one primitive per wood
// triangle) and every leaf as two triangles (geometry leafGeometry(), primitive / 2 is the leaf),
// leaves alpha-tested through their textures by filters that read a TreeRayContext. Shared by
// the bakes that cast rays at the polygonal tree (ambient occlusion, octahedral frames).
class TreeRayScene {
 public:
  explicit TreeRayScene(const Tree& tree);
  ~TreeRayScene();
  TreeRayScene(const TreeRayScene&) = delete;
  TreeRayScene& operator=(const TreeRayScene&) = delete;

  RTCScene scene() const { return mScene; }
  unsigned woodGeometry() const { return mWoodGeometry; }
  unsigned leafGeometry() const { return mLeafGeometry; }

 private:
  RTCDevice mDevice = nullptr;
  RTCScene mScene = nullptr;
  unsigned mWoodGeometry = RTC_INVALID_GEOMETRY_ID;
  unsigned mLeafGeometry = RTC_INVALID_GEOMETRY_ID;
};

// The context every ray at a TreeRayScene is cast with (rtcInitIntersectContext it first).
struct TreeRayContext {
  RTCIntersectContext context;  // first member: Embree passes a pointer to it
  const Tree* tree = nullptr;
  uint32_t sourceLeaf = UINT32_MAX;  // occlusion rays: the leaf they leave from, never a hit
};

// A leaf triangle's hit (primitive, Embree barycentrics) in the leaf's unit square [0, 1]²,
// (0, 0) at corner (−,−): triangles (0,1,2) and (0,2,3) of the corners.
glm::vec2 leafUnitCoordinates(unsigned primitive, float u, float v);

}  // namespace canopy
