#include "viewer/scene_renderer.h"

#include <cmath>

#include "common/error.h"
#include "common/image.h"

namespace canopy {

ViewMode parseViewMode(std::string_view name) {
  if (name == "method") return ViewMode::kMethod;
  if (name == "split") return ViewMode::kSplit;
  if (name == "error") return ViewMode::kError;
  throwInputError("--view: '{}' must be method, split or error", name);
}

SceneRenderer::SceneRenderer(gl::Device& device, Harness& harness)
    : mDevice(device), mHarness(harness) {
  mComposite = mDevice.createProgram(
      {gl::embeddedShader("viewer/composite.vert"), gl::embeddedShader("viewer/composite.frag")});
  mEmptyVao = gl::createVertexArray();
  gl::api().BindVertexArray(0);
}

void SceneRenderer::ensureTargets(glm::ivec2 size) {
  if (mMethodTarget.width == size.x && mMethodTarget.height == size.y) return;
  gl::Device::OwnerScope owner(mDevice, "viewer");
  mMethodTarget = mDevice.createRenderTarget(size.x, size.y, GL_RGBA16F);
  mReferenceTarget = mDevice.createRenderTarget(size.x, size.y, GL_RGBA16F);
}

void SceneRenderer::drawInto(const gl::RenderTarget& target, Method& method, const Camera& camera,
                             const ViewerForest& forest, const SceneOptions& options) {
  const gl::Api& g = gl::api();
  FrameContext frame =
      mHarness.makeFrame(camera, {target.width, target.height}, 1, forest.matrices.id());
  frame.forcedLevel = options.forcedLevel;
  // The shadow pass (lit, shadows on) renders into its own target, so it comes first.
  mHarness.prepareShadows(method, frame, std::span(forest.instances), forest.bounds);
  mHarness.beginFrame(target);
  if (options.wireframe) g.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  method.draw(frame, std::span(forest.instances));
  if (options.wireframe) g.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
}

void SceneRenderer::render(Method& shown, Method& reference, const Camera& camera,
                           const ViewerForest& forest, size_t treeLeaves, glm::ivec2 windowSize,
                           const SceneOptions& options) {
  if (windowSize.x <= 0 || windowSize.y <= 0) return;
  ensureTargets(windowSize);
  mHarness.statistics().begin();
  drawInto(mMethodTarget, shown, camera, forest, options);
  mDrawn = mHarness.statistics().end();
  const double leaves = double(treeLeaves) * double(forest.instances.size());
  mLeafFraction = leaves > 0 ? double(shown.leafPolygonsDrawn()) / leaves : 0.0;
  if (options.mode != ViewMode::kMethod)
    drawInto(mReferenceTarget, reference, camera, forest, options);
  composite(windowSize, options);
}

void SceneRenderer::composite(glm::ivec2 windowSize, const SceneOptions& options) {
  const gl::Api& g = gl::api();
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  g.Viewport(0, 0, windowSize.x, windowSize.y);
  g.Disable(GL_DEPTH_TEST);
  g.Disable(GL_BLEND);
  mComposite.use();
  mComposite.set("uMethod", 0);
  mComposite.set("uReference", 1);
  mComposite.set("uMode", static_cast<int>(options.mode));  // composite.frag: 0, 1, 2 as ViewMode
  mComposite.set("uSplit", options.split);
  const glm::vec3 background = mHarness.settings().background;
  mComposite.set("uBackground", glm::vec3(srgbToLinear(background.r), srgbToLinear(background.g),
                                          srgbToLinear(background.b)));
  g.ActiveTexture(GL_TEXTURE0);
  g.BindTexture(GL_TEXTURE_2D, mMethodTarget.color.id());
  g.ActiveTexture(GL_TEXTURE1);
  g.BindTexture(GL_TEXTURE_2D,
                (options.mode != ViewMode::kMethod ? mReferenceTarget : mMethodTarget).color.id());
  g.ActiveTexture(GL_TEXTURE0);
  g.BindVertexArray(mEmptyVao.id());
  g.DrawArrays(GL_TRIANGLES, 0, 3);
  g.BindVertexArray(0);
}

ImageRgba8 SceneRenderer::screenshot(glm::ivec2 windowSize) const {
  ImageRgbaF pixels(windowSize.x, windowSize.y);
  const gl::Api& g = gl::api();
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  g.ReadBuffer(GL_BACK);
  g.PixelStorei(GL_PACK_ALIGNMENT, 4);
  g.ReadPixels(0, 0, windowSize.x, windowSize.y, GL_RGBA, GL_FLOAT, pixels.pixels.data());
  flipRows(pixels);
  ImageRgba8 image(windowSize.x, windowSize.y);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = uint8_t(std::lround(std::clamp(pixels.pixels[i], 0.0f, 1.0f) * 255.0f));
  return withOpaqueAlpha(image);
}

}  // namespace canopy
