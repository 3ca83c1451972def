#include "bench/popping.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bench/harness.h"
#include "common/metrics.h"

namespace canopy {

std::vector<PathFrame> dollyPath(const Aabb& bounds, const PoppingSettings& settings, float fovY) {
  std::vector<PathFrame> frames;
  const double ratio = double(settings.farDistance) / settings.nearDistance;
  for (int i = 0; i < settings.frames; ++i) {
    const float t = settings.frames > 1 ? float(i) / float(settings.frames - 1) : 0.0f;
    const float distance = settings.nearDistance * float(std::pow(ratio, double(t)));
    frames.push_back({orbitCamera(bounds, {distance, settings.elevation, 30.0f}, fovY), distance});
  }
  return frames;
}

std::vector<PathFrame> orbitPath(const Aabb& bounds, const PoppingSettings& settings, float fovY) {
  std::vector<PathFrame> frames;
  for (int i = 0; i < settings.frames; ++i) {
    const float azimuth = 360.0f * float(i) / float(settings.frames);
    frames.push_back(
        {orbitCamera(bounds, {settings.orbitDistance, settings.elevation, azimuth}, fovY),
         settings.orbitDistance});
  }
  return frames;
}

double rmsDifference(const ImageRgba8& a, const ImageRgba8& b) {
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("rmsDifference: images of different sizes");
  double sum = 0.0;
  const size_t pixels = size_t(a.width) * a.height;
  for (size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) {
      const double d = double(a.pixels[i * 4 + c]) - double(b.pixels[i * 4 + c]);
      sum += d * d;
    }
  }
  return pixels ? std::sqrt(sum / double(pixels * 3)) : 0.0;
}

std::vector<ImageRgba8> renderPath(Harness& harness, Method& method,
                                   const std::vector<PathFrame>& path, int width, int height,
                                   std::vector<uint64_t>& lodSignatures) {
  std::vector<ImageRgba8> frames;
  lodSignatures.clear();
  for (const PathFrame& frame : path) {
    frames.push_back(harness.display(harness.renderLinearAt(method, frame.camera, width, height)));
    lodSignatures.push_back(method.lodSignature());
  }
  return frames;
}

TemporalMetrics temporalMetrics(const std::vector<ImageRgba8>& method,
                                const std::vector<ImageRgba8>& reference,
                                const std::vector<uint64_t>& lodSignatures) {
  if (method.size() != reference.size() || method.size() != lodSignatures.size())
    throw std::invalid_argument("temporalMetrics: sequences of different lengths");
  TemporalMetrics m;
  double sum = 0.0;
  for (size_t i = 0; i < method.size(); ++i) {
    m.psnr.push_back(psnrFromMse(std::pow(rmsDifference(method[i], reference[i]), 2.0)));
    const bool first = i == 0;
    const double change = first ? 0.0 : rmsDifference(method[i], method[i - 1]);
    const double referenceChange = first ? 0.0 : rmsDifference(reference[i], reference[i - 1]);
    m.change.push_back(change);
    m.referenceChange.push_back(referenceChange);
    m.excess.push_back(change - referenceChange);
    m.lodSwitch.push_back(!first && lodSignatures[i] != lodSignatures[i - 1]);
    if (!first) {
      m.peakExcess = std::max(m.peakExcess, m.excess.back());
      sum += m.excess.back();
      m.switches += m.lodSwitch.back() ? 1 : 0;
    }
  }
  m.meanExcess = method.size() > 1 ? sum / double(method.size() - 1) : 0.0;
  return m;
}

}  // namespace canopy
