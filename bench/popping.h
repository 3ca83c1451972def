#pragma once

#include <cstdint>
#include <vector>

#include "common/config.h"
#include "common/image.h"
#include "common/tree.h"
#include "common/views.h"

namespace canopy {

// Where the popping metric looks from (config "popping"). Each field is documented where visit()
// names it.
struct PoppingSettings {
  bool enabled = false;  // the config has "popping"
  int frames = 48;
  float nearDistance = 1.5f;
  float farDistance = 24.0f;
  float elevation = 10.0f;
  float orbitDistance = 6.0f;
  int width = 256;
  int height = 256;

  template <class V>
  void visit(V& v) {
    v("frames", frames, 2, 10'000, "frames per path");
    v("near", nearDistance, 1.01f, 10'000.0f, "dolly: from this distance (bounding radii) ...");
    v("far", farDistance, 1.01f, 100'000.0f, "... to this one, log-spaced");
    v("elevation", elevation, -89.0f, 89.0f, "degrees above the horizon, both paths");
    v("orbit_distance", orbitDistance, 1.01f, 10'000.0f, "orbit: distance (bounding radii)");
    v("resolution", Resolution{width, height}, 16, 8192, "frame size (supersampled like views)");
  }
};

struct PathFrame {
  Camera camera;
  float distance = 0.0f;  // bounding radii, for plots
};

// A dolly from near to far along one direction (log-spaced distances) and a full orbit.
std::vector<PathFrame> dollyPath(const Aabb& bounds, const PoppingSettings& settings, float fovY);
std::vector<PathFrame> orbitPath(const Aabb& bounds, const PoppingSettings& settings, float fovY);

// RMS difference of the RGB of two images of the same size, in 8-bit units.
double rmsDifference(const ImageRgba8& a, const ImageRgba8& b);

// Per frame: PSNR against the reference; the method's frame-to-frame change and the reference's;
// their difference ("temporal excess": change the tree's own motion does not explain); and the
// frames where the method's level-of-detail signature changed. Frame 0 has no change.
struct TemporalMetrics {
  std::vector<double> psnr, change, referenceChange, excess;
  std::vector<bool> lodSwitch;
  double peakExcess = 0.0;
  double meanExcess = 0.0;
  int switches = 0;
};
class Harness;
class Method;
// Renders every frame of a path (one tree at the origin) as the evaluation does, collecting the
// method's LoD signature after each frame.
std::vector<ImageRgba8> renderPath(Harness& harness, Method& method,
                                   const std::vector<PathFrame>& path, int width, int height,
                                   std::vector<uint64_t>& lodSignatures);

TemporalMetrics temporalMetrics(const std::vector<ImageRgba8>& method,
                                const std::vector<ImageRgba8>& reference,
                                const std::vector<uint64_t>& lodSignatures);

}  // namespace canopy
