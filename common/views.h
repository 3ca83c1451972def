#pragma once

#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "common/tree.h"

namespace canopy {

struct Camera {
  glm::vec3 position{0.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovYDegrees = 40.0f;  // vertical field of view
  float nearPlane = 0.1f;
  float farPlane = 100.0f;

  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
};

// One view of an orbit ring: distance from the bounding-sphere centre in bounding-sphere radii,
// elevation above the horizon and azimuth about the up axis (degrees).
struct ViewPose {
  float distance = 4.0f;
  float elevation = 0.0f;
  float azimuth = 0.0f;
};

// Every (distance, elevation, azimuth) combination; azimuths evenly spaced from 0.
std::vector<ViewPose> makeViewRings(const std::vector<float>& distances,
                                    const std::vector<float>& elevations, int azimuthCount);

// A camera on the tree's bounding sphere looking at its centre; at 90° elevation the image's
// up is the horizontal direction away from the camera's azimuth, continuous with lower rings.
Camera orbitCamera(const Aabb& bounds, const ViewPose& pose, float fovYDegrees);

// Cameras photographing a tree as a person walking around it would (Reche et al. 2004, §4):
// `count` views on three rings at 5°, 35° and 65° elevation (about 14:6:2), `distance` bounding
// radii from the centre, azimuths starting at `azimuthOffset` degrees (plus the ring's
// elevation) so they avoid the evaluation's multiples of 90°.
std::vector<Camera> captureRingCameras(const Aabb& bounds, int count, float distance,
                                       float azimuthOffset, float fovYDegrees = 40.0f);

// One tree of a forest: placement in the world.
struct Instance {
  glm::vec3 position{0.0f};
  float rotation = 0.0f;  // about +Y, radians
  float scale = 1.0f;

  glm::mat4 modelMatrix() const;
};

// N trees on a jittered square grid with spacing ~1.6 bounding radii, random rotation about up
// and scale in [0.85, 1.15]; deterministic in the seed.
std::vector<Instance> layoutForest(int count, float treeRadius, uint64_t seed);

// Frame `frame` of `frames` of the benchmark's camera path: an orbit at 15° elevation around the
// forest centre, outside the forest, looking at its centre, so trees are seen from near to far.
Camera forestCamera(const std::vector<Instance>& forest, const Aabb& treeBounds, int frame,
                    int frames, float fovYDegrees);

}  // namespace canopy
