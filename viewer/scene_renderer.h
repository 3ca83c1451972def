#pragma once

#include <span>
#include <string_view>

#include "bench/harness.h"
#include "common/gl/device.h"
#include "common/gl/draw_statistics.h"
#include "methods/method.h"

namespace canopy {

// What the window shows: the method alone, the reference left of a split, or the error heat map.
enum class ViewMode { kMethod, kSplit, kError };
ViewMode parseViewMode(std::string_view name);  // "method" | "split" | "error"

// The forest the viewer draws: its instances, their bounds (the shadow map's extent) and the
// buffer of their matrices.
struct ViewerForest {
  std::vector<Instance> instances;
  Aabb bounds;
  gl::Buffer matrices;
};

struct SceneOptions {
  ViewMode mode = ViewMode::kMethod;
  float split = 0.5f;  // split position in [0, 1]
  bool wireframe = false;
  int forcedLevel = -1;  // >= 0: every method with LoD draws this level
};

// Draws the shown method (and the reference when the mode compares them) into offscreen targets
// through the harness and composites them into the window, counting what the method drew.
class SceneRenderer {
 public:
  SceneRenderer(gl::Device& device, Harness& harness);

  void render(Method& shown, Method& reference, const Camera& camera, const ViewerForest& forest,
              size_t treeLeaves, glm::ivec2 windowSize, const SceneOptions& options);
  const gl::DrawCounts& drawn() const { return mDrawn; }
  double leafGeometryFraction() const { return mLeafFraction; }
  // The window's back buffer as shown, 8-bit sRGB.
  ImageRgba8 screenshot(glm::ivec2 windowSize) const;

 private:
  void ensureTargets(glm::ivec2 size);
  void drawInto(const gl::RenderTarget& target, Method& method, const Camera& camera,
                const ViewerForest& forest, const SceneOptions& options);
  void composite(glm::ivec2 windowSize, const SceneOptions& options);

  gl::Device& mDevice;
  Harness& mHarness;
  gl::Program mComposite;
  gl::VertexArray mEmptyVao;
  gl::RenderTarget mMethodTarget, mReferenceTarget;
  gl::DrawCounts mDrawn;
  double mLeafFraction = 0.0;
};

}  // namespace canopy
