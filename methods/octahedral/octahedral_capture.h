#pragma once

#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "common/image.h"
#include "common/tree.h"
#include "methods/octahedral/octahedral_mapping.h"

namespace canopy {

// How the frames of an octahedral impostor are captured and laid out.
struct OctahedralCaptureSettings {
  OctahedralGrid grid;
  int cellTexels = 128;  // atlas texels per frame side (the frame's image plus its padding)
  int padding = 4;       // transparent texels around each frame's image, so filtering stays inside
  int supersample = 2;   // rays per texel side
  bool wood = true;      // the trunk and branches are captured too (false: leaves only)
};

// The frames as two atlases of N×N cells, frame (i, j) in cell column i, row j (row 0 first in
// the pixel arrays, i.e. texture v = 0). Each frame is an orthographic view of the bounding
// sphere (centre, radius) along −frameDirection, the image axes from frameAxes(): the sphere's
// square spans the cell's inner (cellTexels − 2·padding)² texels.
struct OctahedralFrames {
  // sRGB colour (the linear mean of covered rays) with alpha the covered fraction of the
  // texel's rays; transparent texels take their covered neighbours' colour (dilated).
  ImageRgba8 color;
  // RGB the mean normal (tree space, turned towards the frame's camera) as n · 0.5 + 0.5; A the
  // mean depth along the frame's view, 0 at the sphere's near side, 1 at its far side. Empty
  // texels are dilated from covered ones, and beyond that hold the sphere's centre plane.
  ImageRgba8 normalDepth;
  glm::vec3 center{0.0f};
  float radius = 1.0f;
  double coveredFraction = 0.0;  // mean alpha over the frames' inner squares
};

// Casts the frames' rays at the polygonal tree with Embree (methods/common/tree_rays.h): wood
// coloured as the reference draws it (base colour × texture), leaves by the image of the side
// the ray sees, alpha-tested. Deterministic; parallel over frames.
OctahedralFrames captureOctahedralFrames(const Tree& tree,
                                         const OctahedralCaptureSettings& settings);

// A 2 × 2 box filter of every channel (the normal-depth atlas's mip levels and its reduced
// resolution): odd sizes keep their last row or column. Straight averages are right here because
// empty texels were dilated.
ImageRgba8 halveImage(const ImageRgba8& image);

// Each frame's covered rectangle (any texel with alpha > 0), grown by `marginTexels`, as
// (x0, y0, x1, y1) in the frame's image coordinates: −1 … 1 across the sphere's square, x along
// the frame's right axis, y along its up. Frame (i, j) at index j · N + i; an empty frame gets
// an empty rectangle (x0 > x1). The draw cuts each quad to its frames' rectangles.
std::vector<glm::vec4> frameCoverageRects(const ImageRgba8& color, int frames, int cellTexels,
                                          int padding, int marginTexels);

}  // namespace canopy
