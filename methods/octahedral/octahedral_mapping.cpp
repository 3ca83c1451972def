#include "methods/octahedral/octahedral_mapping.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace canopy {
namespace {

glm::vec2 signNotZero(glm::vec2 v) {
  return {v.x >= 0.0f ? 1.0f : -1.0f, v.y >= 0.0f ? 1.0f : -1.0f};
}

}  // namespace

glm::vec3 OctahedralGrid::clampDirection(glm::vec3 d) const {
  if (!hemisphere || d.y >= 0.0f) return d;
  d.y = 0.0f;
  const float length = glm::length(d);
  return length > 1e-6f ? d / length : glm::vec3(1.0f, 0.0f, 0.0f);
}

glm::vec2 OctahedralGrid::encode(glm::vec3 direction) const {
  const glm::vec3 d = clampDirection(direction);
  const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  const glm::vec2 q = glm::vec2(d.x, d.z) / std::max(l1, 1e-20f);
  if (hemisphere) return {q.x + q.y, q.x - q.y};  // the upper diamond turned 45° onto the square
  if (d.y >= 0.0f) return q;
  return (1.0f - glm::abs(glm::vec2(q.y, q.x))) * signNotZero(q);  // the lower half folded out
}

glm::vec3 OctahedralGrid::decode(glm::vec2 p) const {
  glm::vec3 d;
  if (hemisphere) {
    const glm::vec2 q(0.5f * (p.x + p.y), 0.5f * (p.x - p.y));
    d = {q.x, 1.0f - std::abs(q.x) - std::abs(q.y), q.y};
  } else {
    d = {p.x, 1.0f - std::abs(p.x) - std::abs(p.y), p.y};
    if (d.y < 0.0f) {
      const glm::vec2 folded = (1.0f - glm::abs(glm::vec2(d.z, d.x))) * signNotZero({d.x, d.z});
      d.x = folded.x;
      d.z = folded.y;
    }
  }
  return glm::normalize(d);
}

glm::vec3 OctahedralGrid::frameDirection(glm::ivec2 frame) const {
  return decode(glm::vec2(frame) / float(frames - 1) * 2.0f - 1.0f);
}

FrameBlend blendFrames(const OctahedralGrid& grid, glm::vec3 direction) {
  const float last = float(grid.frames - 1);
  const glm::vec2 g = glm::clamp((grid.encode(direction) * 0.5f + 0.5f) * last, 0.0f, last);
  const glm::ivec2 cell = glm::min(glm::ivec2(glm::floor(g)), glm::ivec2(grid.frames - 2));
  const glm::vec2 f = g - glm::vec2(cell);
  FrameBlend blend;
  if (f.x + f.y <= 1.0f) {
    blend.frames = {cell, cell + glm::ivec2(1, 0), cell + glm::ivec2(0, 1)};
    blend.weights = {1.0f - f.x - f.y, f.x, f.y};
  } else {
    blend.frames = {cell + glm::ivec2(1, 1), cell + glm::ivec2(0, 1), cell + glm::ivec2(1, 0)};
    blend.weights = {f.x + f.y - 1.0f, 1.0f - f.x, 1.0f - f.y};
  }
  return blend;
}

FrameAxes frameAxes(glm::vec3 toCamera) {
  const glm::vec3 reference =
      std::abs(toCamera.y) > 0.999f ? glm::vec3(0.0f, 0.0f, -1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::vec3 right = glm::normalize(glm::cross(reference, toCamera));
  return {right, glm::cross(toCamera, right)};
}

}  // namespace canopy
