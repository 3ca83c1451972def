#pragma once

#include <filesystem>

#include "common/gl/context.h"
#include "common/tree.h"

namespace canopy {

struct CaptureExportOptions {
  int trainViews = 22;    // photographs to reconstruct from
  int testViews = 8;      // held-out photographs to score on
  int resolution = 512;   // pixels per side
  float distance = 3.0f;  // camera distance in bounding radii
  int supersample = 2;    // coverage samples per pixel side
};

// Photographs a mesh tree through the polygonal reference into a NeRF-layout folder, so the
// capture path (and other tools that read this layout) can be exercised on a known tree.
// Train and test cameras lie on the same rings at different azimuths.
void exportCaptures(const Tree& tree, const std::filesystem::path& folder,
                    const CaptureExportOptions& options, gl::Backend backend);

}  // namespace canopy
