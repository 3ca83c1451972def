#include "viewer/camera_controller.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace canopy {

void CameraController::frameTree(const Aabb& bounds) {
  mCenter = bounds.center();
  mRadius = std::max(0.5f * glm::length(bounds.extent()), 1e-3f);
  mDistance = 3.0f * mRadius;
  mSpeed = mRadius;
  mYaw = 30.0f;
  mPitch = 15.0f;
  mPosition = mCenter - forward() * mDistance;
}

void CameraController::setMode(Mode mode) {
  if (mode == Mode::kOrbit && mMode == Mode::kFly) {
    // Orbit again around the centre at the current distance.
    mDistance = std::max(glm::length(mPosition - mCenter), 0.1f * mRadius);
  } else if (mode == Mode::kFly && mMode == Mode::kOrbit) {
    mPosition = mCenter - forward() * mDistance;
  }
  mMode = mode;
}

glm::vec3 CameraController::forward() const {
  const float yaw = glm::radians(mYaw), pitch = glm::radians(mPitch);
  // Looking from +Z towards the centre at yaw 0, down for positive pitch.
  return glm::normalize(glm::vec3(-std::sin(yaw) * std::cos(pitch), -std::sin(pitch),
                                  -std::cos(yaw) * std::cos(pitch)));
}

void CameraController::update(glm::vec2 dragPixels, float wheel, glm::vec3 move, float seconds) {
  mYaw += 0.3f * dragPixels.x;
  mPitch = std::clamp(mPitch + 0.3f * dragPixels.y, -89.0f, 89.0f);
  if (mMode == Mode::kOrbit) {
    mDistance = std::clamp(mDistance * std::pow(0.9f, wheel), 0.2f * mRadius, 500.0f * mRadius);
    return;
  }
  mSpeed = std::clamp(mSpeed * std::pow(1.25f, wheel), 0.01f * mRadius, 100.0f * mRadius);
  const glm::vec3 f = forward();
  const glm::vec3 right = glm::normalize(glm::cross(f, glm::vec3(0, 1, 0)));
  mPosition += (right * move.x + glm::vec3(0, 1, 0) * move.y + f * move.z) * mSpeed * seconds;
}

Camera CameraController::camera(float fovYDegrees) const {
  Camera camera;
  const glm::vec3 f = forward();
  camera.position = mMode == Mode::kOrbit ? mCenter - f * mDistance : mPosition;
  camera.target = camera.position + f;
  camera.up = glm::vec3(0, 1, 0);
  camera.fovYDegrees = fovYDegrees;
  const float distance = glm::length(camera.position - mCenter);
  camera.nearPlane = std::max(0.01f * mRadius, 0.5f * (distance - mRadius));
  camera.farPlane = distance + 2000.0f * mRadius;
  return camera;
}

nlohmann::json CameraController::toJson() const {
  const Camera c = camera(40.0f);
  return {{"mode", mMode == Mode::kOrbit ? "orbit" : "fly"},
          {"yaw", mYaw},
          {"pitch", mPitch},
          {"distance", mDistance},
          {"position", {c.position.x, c.position.y, c.position.z}},
          {"target", {c.target.x, c.target.y, c.target.z}},
          {"up", {c.up.x, c.up.y, c.up.z}}};
}

void CameraController::fromJson(const nlohmann::json& json) {
  mYaw = json.at("yaw");
  mPitch = json.at("pitch");
  mDistance = json.at("distance");
  const auto& p = json.at("position");
  mPosition = {p.at(0).get<float>(), p.at(1).get<float>(), p.at(2).get<float>()};
  mMode = json.at("mode") == "fly" ? Mode::kFly : Mode::kOrbit;
}

}  // namespace canopy
