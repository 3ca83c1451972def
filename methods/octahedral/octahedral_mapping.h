#pragma once

#include <array>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace canopy {

// The octahedral view grid of an octahedral impostor (Brucks 2018): N×N frames whose view
// directions lie on an octahedron (the whole sphere) or a hemi-octahedron (the upper half, +Y up)
// unfolded onto the square [−1, 1]². octahedral.vert implements the same functions in GLSL; the
// tests hold both to these.
struct OctahedralGrid {
  int frames = 16;         // frames per side (N ≥ 2): frame (i, j) sits at grid point (i, j)
  bool hemisphere = true;  // upper hemisphere only: views from below use the horizon's frames

  // Square coordinates of a unit direction (towards the viewer, tree space). Hemisphere: a
  // direction below the horizon is first clamped onto it.
  glm::vec2 encode(glm::vec3 direction) const;
  // The unit direction at square coordinates p ∈ [−1, 1]².
  glm::vec3 decode(glm::vec2 p) const;
  // The direction of frame (i, j), i and j in [0, N).
  glm::vec3 frameDirection(glm::ivec2 frame) const;
  // The clamp encode() applies: directions below the horizon moved onto it (hemisphere only).
  glm::vec3 clampDirection(glm::vec3 direction) const;
};

// The three frames around a view direction: the corners of the grid triangle its square
// coordinates fall in, with barycentric weights (non-negative, summing to 1).
struct FrameBlend {
  std::array<glm::ivec2, 3> frames;
  glm::vec3 weights{1.0f, 0.0f, 0.0f};
};
FrameBlend blendFrames(const OctahedralGrid& grid, glm::vec3 direction);

// The image axes of an orthographic frame looking along −toCamera: right and up, both unit and
// perpendicular to it (world +Y projects upwards; a view straight down has −Z up).
struct FrameAxes {
  glm::vec3 right;
  glm::vec3 up;
};
FrameAxes frameAxes(glm::vec3 toCamera);

}  // namespace canopy
