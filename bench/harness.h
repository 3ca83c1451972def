#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "common/gl/device.h"
#include "common/image.h"
#include "common/views.h"
#include "methods/method.h"

namespace canopy {

// How every image is made, for the reference and every method alike.
struct RenderSettings {
  int width = 512;  // evaluation resolution
  int height = 512;
  int supersample = 2;        // rendered at width·s × height·s, box-filtered down
  float fovYDegrees = 40.0f;  // vertical field of view
  Shading shading = Shading::kUnlit;
  glm::vec3 background{0.5f, 0.6f, 0.75f};     // sRGB, the colour images are composited over
  glm::vec3 lightDirection{0.3f, 0.8f, 0.5f};  // towards the light (normalised on use)
  float ambient = 0.35f;
  bool shadows = false;      // lit only: a shadow map rendered with the method itself each frame
  int shadowMapSize = 2048;  // texels per side
};

struct FrameTimes {
  double medianMs = 0.0;
  double p95Ms = 0.0;
  double meanMs = 0.0;
  int frames = 0;
};

// Renders views and times forests for any method, through the same GL state and targets.
class Harness {
 public:
  Harness(gl::Device& device, RenderSettings settings);

  const RenderSettings& settings() const { return mSettings; }
  RenderSettings& settings() { return mSettings; }  // the viewer changes shading live
  // The single tree's bounds (at the origin), which its shadow map must cover.
  void setTreeBounds(const Aabb& bounds) { mTreeBounds = bounds; }

  // The frame every draw gets, and the GL state every method starts from, bound to `target`:
  // what renderLinear and timeForest use, for callers that draw into their own targets.
  FrameContext makeFrame(const Camera& camera, int width, int height, GLuint instances) const;
  void beginFrame(const gl::RenderTarget& target);

  // One tree at the origin seen by `camera`: the supersampled render box-filtered to the
  // evaluation resolution (linear, premultiplied; alpha is coverage).
  ImageRgbaF renderLinear(Method& method, const Camera& camera);
  // The same at another resolution (still supersampled by settings().supersample).
  ImageRgbaF renderLinearAt(Method& method, const Camera& camera, int width, int height);
  // A linear premultiplied image composited over the background, 8-bit sRGB (alpha keeps
  // coverage): how every scored image is made, rendered or captured.
  ImageRgba8 display(const ImageRgbaF& linear) const;
  // The same composited over the background and encoded to 8-bit sRGB (alpha keeps coverage).
  ImageRgba8 render(Method& method, const Camera& camera);

  // Frame times of the forest seen along the benchmark's camera path, glFinish after each frame,
  // after `warmup` unmeasured frames, at width × height without supersampling.
  // A non-empty `path` replaces the orbit: frame i looks from path[i % path.size()].
  FrameTimes timeForest(Method& method, const std::vector<Instance>& forest, const Aabb& treeBounds,
                        int frames, int warmup, int width, int height,
                        const std::vector<Camera>& path = {});

  // A frame of a forest as an image (for checks and figures).
  ImageRgba8 renderForestFrame(Method& method, const std::vector<Instance>& forest,
                               const Aabb& treeBounds, int frame, int frames, int width,
                               int height);

  // Lit and shadowed frames (settings().shadows): renders the method's depth from the light over
  // `scene` (LoD chosen from the viewer's position, so close trees shadow with full evaluation and
  // far ones with their coarse levels) and fills the frame's shadow fields, binding the map for
  // the draw that follows. Does nothing for unlit frames.
  void prepareShadows(Method& method, FrameContext& frame, std::span<const Instance> instances,
                      const Aabb& scene);

 private:
  gl::RenderTarget& targetOfSize(int width, int height);
  void uploadInstances(const std::vector<Instance>& instances);

  gl::Device& mDevice;
  RenderSettings mSettings;
  std::vector<gl::RenderTarget> mTargets;
  gl::Buffer mInstances;
  std::vector<Instance> mUploadedInstances;
  Aabb mTreeBounds;
  gl::ShadowMap mShadowMap;
};

// The bounds of every instance of a tree with bounds `tree`.
Aabb forestBounds(const std::vector<Instance>& forest, const Aabb& tree);

// Median and 95th percentile (nearest rank) of frame times in milliseconds.
FrameTimes summarizeFrameTimes(std::vector<double> milliseconds);

}  // namespace canopy
