#include "common/views.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "common/random.h"

namespace canopy {
namespace {
constexpr float kPi = 3.14159265358979f;
float radians(float degrees) {
  return degrees * kPi / 180.0f;
}
}  // namespace

glm::mat4 Camera::view() const {
  return glm::lookAt(position, target, up);
}

glm::mat4 Camera::projection(float aspect) const {
  return glm::perspective(radians(fovYDegrees), aspect, nearPlane, farPlane);
}

std::vector<ViewPose> makeViewRings(const std::vector<float>& distances,
                                    const std::vector<float>& elevations, int azimuthCount) {
  std::vector<ViewPose> poses;
  for (float distance : distances) {
    for (float elevation : elevations) {
      for (int a = 0; a < azimuthCount; ++a) {
        poses.push_back({distance, elevation, 360.0f * float(a) / float(azimuthCount)});
      }
    }
  }
  return poses;
}

Camera orbitCamera(const Aabb& bounds, const ViewPose& pose, float fovYDegrees) {
  const float radius = 0.5f * glm::length(bounds.extent());
  const float elevation = radians(pose.elevation), azimuth = radians(pose.azimuth);
  const glm::vec3 horizontal(std::sin(azimuth), 0.0f, std::cos(azimuth));
  const glm::vec3 direction =
      horizontal * std::cos(elevation) + glm::vec3(0, std::sin(elevation), 0);
  Camera camera;
  camera.target = bounds.center();
  camera.position = camera.target + direction * (pose.distance * radius);
  camera.up = std::abs(std::sin(elevation)) > 0.999f ? -horizontal : glm::vec3(0, 1, 0);
  camera.fovYDegrees = fovYDegrees;
  // The near plane stays in front of the bounding sphere; depth precision follows the distance.
  camera.nearPlane = std::max(0.02f * radius, (pose.distance - 1.0f) * radius * 0.5f);
  camera.farPlane = (pose.distance + 1.5f) * radius;
  return camera;
}

std::vector<Camera> captureRingCameras(const Aabb& bounds, int count, float distance,
                                       float azimuthOffset, float fovYDegrees) {
  const int high = std::max(1, int(std::lround(count * 2.0 / 22.0)));
  const int middle = std::max(1, int(std::lround(count * 6.0 / 22.0)));
  const int low = std::max(1, count - high - middle);
  const std::pair<float, int> rings[3] = {{5.0f, low}, {35.0f, middle}, {65.0f, high}};
  std::vector<Camera> cameras;
  for (const auto& [elevation, n] : rings) {
    for (int i = 0; i < n && int(cameras.size()) < count; ++i) {
      const float azimuth = azimuthOffset + 360.0f * float(i) / float(n) + elevation;
      cameras.push_back(orbitCamera(bounds, {distance, elevation, azimuth}, fovYDegrees));
    }
  }
  return cameras;
}

glm::mat4 Instance::modelMatrix() const {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), position);
  m = glm::rotate(m, rotation, glm::vec3(0, 1, 0));
  return glm::scale(m, glm::vec3(scale));
}

std::vector<Instance> layoutForest(int count, float treeRadius, uint64_t seed) {
  Random random(seed, 0x5851f42d4c957f2dULL);
  std::vector<Instance> forest;
  if (count <= 0) return forest;
  const int side = static_cast<int>(std::ceil(std::sqrt(float(count))));
  const float spacing = 1.6f * treeRadius;
  const float offset = 0.5f * float(side - 1) * spacing;
  for (int i = 0; i < count; ++i) {
    Instance instance;
    const int gx = i % side, gz = i / side;
    const float jitter = count > 1 ? 0.25f * spacing : 0.0f;
    instance.position = {float(gx) * spacing - offset + random.uniform(-1, 1) * jitter, 0.0f,
                         float(gz) * spacing - offset + random.uniform(-1, 1) * jitter};
    instance.rotation = count > 1 ? random.uniform(0.0f, 2.0f * kPi) : 0.0f;
    instance.scale = count > 1 ? random.uniform(0.85f, 1.15f) : 1.0f;
    forest.push_back(instance);
  }
  return forest;
}

Camera forestCamera(const std::vector<Instance>& forest, const Aabb& treeBounds, int frame,
                    int frames, float fovYDegrees) {
  const float treeRadius = 0.5f * glm::length(treeBounds.extent());
  float extent = 0.0f;
  for (const Instance& instance : forest) {
    extent = std::max(extent, glm::length(glm::vec2(instance.position.x, instance.position.z)));
  }
  const float orbitRadius = extent + 2.5f * treeRadius;
  const float angle = 2.0f * kPi * float(frame) / float(std::max(frames, 1));
  const float elevation = radians(15.0f);
  Camera camera;
  camera.target = glm::vec3(0.0f, treeBounds.center().y, 0.0f);
  camera.position = camera.target + orbitRadius * glm::vec3(std::sin(angle) * std::cos(elevation),
                                                            std::sin(elevation),
                                                            std::cos(angle) * std::cos(elevation));
  camera.fovYDegrees = fovYDegrees;
  camera.nearPlane = 0.05f * treeRadius;
  camera.farPlane = 2.0f * orbitRadius + 2.0f * treeRadius;
  return camera;
}

}  // namespace canopy
