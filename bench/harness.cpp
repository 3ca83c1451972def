#include "bench/harness.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace canopy {

// The light direction is normalised where it is used (makeFrame, prepareShadows): the viewer
// edits it live.
Harness::Harness(gl::Device& device, RenderSettings settings)
    : mDevice(device), mSettings(settings) {}

gl::RenderTarget& Harness::targetOfSize(int width, int height) {
  for (gl::RenderTarget& target : mTargets) {
    if (target.width == width && target.height == height) return target;
  }
  gl::Device::OwnerScope owner(mDevice, "harness");
  mTargets.push_back(mDevice.createRenderTarget(width, height, GL_RGBA16F));
  return mTargets.back();
}

void Harness::uploadInstances(const std::vector<Instance>& instances) {
  if (mInstances.id() != 0 && instances.size() == mUploadedInstances.size() &&
      std::equal(instances.begin(), instances.end(), mUploadedInstances.begin(),
                 [](const Instance& a, const Instance& b) {
                   return a.position == b.position && a.rotation == b.rotation &&
                          a.scale == b.scale;
                 })) {
    return;
  }
  std::vector<glm::mat4> matrices;
  matrices.reserve(instances.size());
  for (const Instance& instance : instances) matrices.push_back(instance.modelMatrix());
  gl::Device::OwnerScope owner(mDevice, "harness");
  mInstances = mDevice.createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER, matrices,
                                    "instance matrices");
  mUploadedInstances = instances;
}

FrameContext Harness::makeFrame(const Camera& camera, int width, int height,
                                GLuint instances) const {
  FrameContext frame;
  frame.view = camera.view();
  frame.projection = camera.projection(float(width) / float(height));
  frame.cameraPosition = camera.position;
  frame.viewportSize = {width, height};
  frame.shading = mSettings.shading;
  frame.lightDirection = glm::normalize(mSettings.lightDirection);
  frame.ambient = mSettings.ambient;
  frame.instanceBuffer = instances;
  return frame;
}

namespace {
// The state every method's draw starts from; methods restore anything else they change.
void resetDrawState(const gl::Api& g) {
  g.Enable(GL_DEPTH_TEST);
  g.DepthFunc(GL_LESS);
  g.DepthMask(GL_TRUE);
  g.Disable(GL_BLEND);
  g.Disable(GL_CULL_FACE);
}
}  // namespace

void Harness::beginFrame(const gl::RenderTarget& target) {
  const gl::Api& g = gl::api();
  g.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer.id());
  g.Viewport(0, 0, target.width, target.height);
  resetDrawState(g);
  g.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  const float transparent[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  g.ClearBufferfv(GL_COLOR, 0, transparent);
  g.Clear(GL_DEPTH_BUFFER_BIT);
}

ImageRgbaF Harness::renderLinear(Method& method, const Camera& camera) {
  return renderLinearAt(method, camera, mSettings.width, mSettings.height);
}

Aabb forestBounds(const std::vector<Instance>& forest, const Aabb& tree) {
  Aabb bounds;
  for (const Instance& instance : forest) {
    const glm::mat4 model = instance.modelMatrix();
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 corner(c & 1 ? tree.max.x : tree.min.x, c & 2 ? tree.max.y : tree.min.y,
                             c & 4 ? tree.max.z : tree.min.z);
      bounds.extend(glm::vec3(model * glm::vec4(corner, 1.0f)));
    }
  }
  return bounds;
}

void Harness::prepareShadows(Method& method, FrameContext& frame,
                             std::span<const Instance> instances, const Aabb& scene) {
  // The shadow pass draws depth only (unlit variant); the frame's draw then uses its shading's.
  gl::selectLitVariant(false);
  const bool lit = frame.shading == Shading::kLit;
  if (!mSettings.shadows || !lit || scene.empty()) {
    gl::selectLitVariant(lit);
    return;
  }
  const gl::Api& g = gl::api();
  if (mShadowMap.size != mSettings.shadowMapSize) {
    gl::Device::OwnerScope owner(mDevice, "harness");
    mShadowMap = mDevice.createShadowMap(mSettings.shadowMapSize);
  }
  const glm::vec3 light = glm::normalize(mSettings.lightDirection), center = scene.center();
  const float radius = std::max(0.5f * glm::length(scene.extent()), 1e-4f);
  const glm::vec3 up = std::abs(light.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
  FrameContext shadow = frame;
  shadow.view = glm::lookAt(center + light * (2.0f * radius), center, up);
  shadow.projection = glm::ortho(-radius, radius, -radius, radius, 0.5f * radius, 3.5f * radius);
  shadow.viewportSize = {mShadowMap.size, mShadowMap.size};
  shadow.shading = Shading::kUnlit;  // depth only; LoD still follows frame.cameraPosition
  shadow.shadowMap = 0;
  g.BindFramebuffer(GL_FRAMEBUFFER, mShadowMap.framebuffer.id());
  g.Viewport(0, 0, mShadowMap.size, mShadowMap.size);
  resetDrawState(g);
  g.Clear(GL_DEPTH_BUFFER_BIT);
  g.Enable(GL_POLYGON_OFFSET_FILL);
  g.PolygonOffset(1.5f, 4.0f);
  method.draw(shadow, instances);
  g.Disable(GL_POLYGON_OFFSET_FILL);
  frame.shadowMap = mShadowMap.depth.id();
  frame.lightViewProjection = shadow.projection * shadow.view;
  g.ActiveTexture(GL_TEXTURE0 + kShadowMapUnit);
  g.BindTexture(GL_TEXTURE_2D, frame.shadowMap);
  g.ActiveTexture(GL_TEXTURE0);
  gl::selectLitVariant(true);  // the lit draw that follows samples the map
}

ImageRgbaF Harness::renderLinearAt(Method& method, const Camera& camera, int width, int height) {
  const int s = mSettings.supersample;
  gl::RenderTarget& target = targetOfSize(width * s, height * s);
  uploadInstances({Instance{}});
  FrameContext frame = makeFrame(camera, target.width, target.height, mInstances.id());
  prepareShadows(method, frame, std::span(mUploadedInstances), mTreeBounds);
  beginFrame(target);
  method.draw(frame, std::span(mUploadedInstances));
  const gl::Api& g = gl::api();
  ImageRgbaF full(target.width, target.height);
  g.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer.id());
  g.ReadBuffer(GL_COLOR_ATTACHMENT0);
  g.PixelStorei(GL_PACK_ALIGNMENT, 4);
  g.ReadPixels(0, 0, target.width, target.height, GL_RGBA, GL_FLOAT, full.pixels.data());
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl::checkError("Harness::renderLinear");
  flipRows(full);
  return boxDownsample(full, s);
}

ImageRgba8 Harness::display(const ImageRgbaF& linear) const {
  const glm::vec3 background(srgbToLinear(mSettings.background.r),
                             srgbToLinear(mSettings.background.g),
                             srgbToLinear(mSettings.background.b));
  return compositeToSrgb8(linear, background);
}

ImageRgba8 Harness::render(Method& method, const Camera& camera) {
  return display(renderLinear(method, camera));
}

FrameTimes summarizeFrameTimes(std::vector<double> milliseconds) {
  FrameTimes times;
  times.frames = static_cast<int>(milliseconds.size());
  if (milliseconds.empty()) return times;
  std::sort(milliseconds.begin(), milliseconds.end());
  const size_t n = milliseconds.size();
  times.medianMs =
      n % 2 ? milliseconds[n / 2] : 0.5 * (milliseconds[n / 2 - 1] + milliseconds[n / 2]);
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * double(n)));
  times.p95Ms = milliseconds[std::clamp<size_t>(rank, 1, n) - 1];
  times.meanMs = std::accumulate(milliseconds.begin(), milliseconds.end(), 0.0) / double(n);
  return times;
}

FrameTimes Harness::timeForest(Method& method, const std::vector<Instance>& forest,
                               const Aabb& treeBounds, int frames, int warmup, int width,
                               int height, const std::vector<Camera>& path) {
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest);
  const gl::Api& g = gl::api();
  const Aabb scene = forestBounds(forest, treeBounds);
  std::vector<double> times;
  g.Finish();
  for (int i = 0; i < warmup + frames; ++i) {
    const int pathFrame = i < warmup ? i : i - warmup;
    const Camera camera =
        path.empty() ? forestCamera(forest, treeBounds, pathFrame, frames, mSettings.fovYDegrees)
                     : path[size_t(i) % path.size()];
    const auto start = std::chrono::steady_clock::now();
    FrameContext frameContext = makeFrame(camera, width, height, mInstances.id());
    prepareShadows(method, frameContext, std::span(mUploadedInstances), scene);
    beginFrame(target);
    method.draw(frameContext, std::span(mUploadedInstances));
    g.Finish();
    const auto end = std::chrono::steady_clock::now();
    if (i >= warmup)
      times.push_back(std::chrono::duration<double, std::milli>(end - start).count());
  }
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl::checkError("Harness::timeForest");
  return summarizeFrameTimes(std::move(times));
}

ImageRgba8 Harness::renderForestFrame(Method& method, const std::vector<Instance>& forest,
                                      const Aabb& treeBounds, int frame, int frames, int width,
                                      int height) {
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest);
  const Camera camera = forestCamera(forest, treeBounds, frame, frames, mSettings.fovYDegrees);
  FrameContext frameContext = makeFrame(camera, width, height, mInstances.id());
  prepareShadows(method, frameContext, std::span(mUploadedInstances),
                 forestBounds(forest, treeBounds));
  beginFrame(target);
  method.draw(frameContext, std::span(mUploadedInstances));
  ImageRgbaF image(width, height);
  const gl::Api& g = gl::api();
  g.ReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, image.pixels.data());
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  flipRows(image);
  return display(image);
}

}  // namespace canopy
