#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "common/views.h"

namespace canopy {

// Fly (WASD + mouse look, wheel sets speed) and orbit (drag to turn around a centre, wheel
// zooms) cameras for the viewer.
class CameraController {
 public:
  enum class Mode { kOrbit, kFly };

  void frameTree(const Aabb& bounds);  // orbit the tree from 3 radii
  void setMode(Mode mode);
  Mode mode() const { return mMode; }

  // Input of one frame: mouse motion while dragging (pixels), wheel steps, movement keys
  // (x: right, y: up, z: forward, each −1..1) and the frame's duration.
  void update(glm::vec2 dragPixels, float wheel, glm::vec3 move, float seconds);

  Camera camera(float fovYDegrees) const;
  float speed() const { return mSpeed; }

  nlohmann::json toJson() const;
  void fromJson(const nlohmann::json& json);  // throws nlohmann::json::exception on bad input

 private:
  glm::vec3 forward() const;

  Mode mMode = Mode::kOrbit;
  glm::vec3 mCenter{0.0f};                // orbit centre
  float mRadius = 1.0f;                   // tree bounding radius (scales near/far planes and speed)
  float mDistance = 3.0f;                 // orbit distance
  float mYaw = 30.0f;                     // degrees about +Y
  float mPitch = 15.0f;                   // degrees above the horizon
  glm::vec3 mPosition{0.0f, 0.0f, 5.0f};  // fly position
  float mSpeed = 1.0f;                    // fly speed, world units per second
};

}  // namespace canopy
