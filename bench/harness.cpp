#include "bench/harness.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace canopy {

// The light direction is normalised where it is used (makeFrame, prepareShadows): the viewer
// edits it live.
Harness::Harness(gl::Device& device, RenderSettings settings)
    : mDevice(device), mSettings(settings) {}

Harness::~Harness() = default;

void Harness::setTree(const Aabb& bounds, size_t leaves) {
  mTreeBounds = bounds;
  mTreeLeaves = leaves;
}

gl::DrawStatistics& Harness::statistics() {
  if (!mStatistics) mStatistics = std::make_unique<gl::DrawStatistics>();
  return *mStatistics;
}

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

FrameContext Harness::makeFrame(const Camera& camera, glm::ivec2 outputSize, int supersample,
                                GLuint instances) const {
  FrameContext frame;
  frame.view = camera.view();
  frame.projection = camera.projection(float(outputSize.x) / float(outputSize.y));
  frame.cameraPosition = camera.position;
  frame.targetSize = outputSize * supersample;
  frame.lodFocalPixels =
      0.5f * float(outputSize.y) / std::tan(0.5f * glm::radians(camera.fovYDegrees));
  frame.targetPixelsPerOutputPixel = float(supersample);
  frame.shading = mSettings.shading;
  frame.lightDirection = glm::normalize(mSettings.lightDirection);
  frame.ambient = mSettings.ambient;
  frame.ambientOcclusion = mSettings.ambientOcclusion;
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

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
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
  // The viewer's LoD inputs (position, output focal length) stay: shadows follow what is seen.
  FrameContext shadow = frame;
  shadow.view = glm::lookAt(center + light * (2.0f * radius), center, up);
  shadow.projection = glm::ortho(-radius, radius, -radius, radius, 0.5f * radius, 3.5f * radius);
  shadow.targetSize = {mShadowMap.size, mShadowMap.size};
  shadow.targetPixelsPerOutputPixel = 1.0f;  // shader LoD measures the map's own texels
  shadow.shading = Shading::kUnlit;
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

void Harness::drawFrame(Method& method, const gl::RenderTarget& target, FrameContext frame,
                        const Aabb& scene, DrawnStats* drawn) {
  if (drawn) statistics().begin();
  prepareShadows(method, frame, std::span(mUploadedInstances), scene);
  beginFrame(target);
  method.draw(frame, std::span(mUploadedInstances));
  if (drawn) {
    drawn->counts = mStatistics->end();
    const double leaves = double(mTreeLeaves) * double(mUploadedInstances.size());
    drawn->leafGeometryFraction = leaves > 0 ? double(method.leafPolygonsDrawn()) / leaves : 0.0;
  }
}

ImageRgbaF Harness::readTarget(const gl::RenderTarget& target) const {
  const gl::Api& g = gl::api();
  ImageRgbaF image(target.width, target.height);
  g.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer.id());
  g.ReadBuffer(GL_COLOR_ATTACHMENT0);
  g.PixelStorei(GL_PACK_ALIGNMENT, 4);
  g.ReadPixels(0, 0, target.width, target.height, GL_RGBA, GL_FLOAT, image.pixels.data());
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  flipRows(image);
  return image;
}

ImageRgbaF Harness::renderLinear(Method& method, const Camera& camera) {
  return renderLinearAt(method, camera, mSettings.width, mSettings.height);
}

ImageRgbaF Harness::renderLinearAt(Method& method, const Camera& camera, int width, int height,
                                   DrawnStats* drawn) {
  const int s = mSettings.supersample;
  gl::RenderTarget& target = targetOfSize(width * s, height * s);
  uploadInstances({Instance{}});
  drawFrame(method, target, makeFrame(camera, {width, height}, s, mInstances.id()), mTreeBounds,
            drawn);
  gl::checkError("Harness::renderLinear");
  return boxDownsample(readTarget(target), s);
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

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const double position = std::clamp(q, 0.0, 1.0) * double(values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(position));
  const size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (position - double(below)) * (values[above] - values[below]);
}

Camera forestPathCamera(const ForestTiming& timing, const std::vector<Instance>& forest,
                        const Aabb& treeBounds, int frame, float fovYDegrees) {
  if (!timing.path.empty()) return timing.path[size_t(frame) % timing.path.size()];
  return forestCamera(forest, treeBounds, frame, timing.frames, fovYDegrees);
}

double Harness::timeFrame(Method& method, const gl::RenderTarget& target, const Camera& camera,
                          int width, int height, const Aabb& scene) {
  const auto start = std::chrono::steady_clock::now();
  drawFrame(method, target, makeFrame(camera, {width, height}, 1, mInstances.id()), scene, nullptr);
  gl::api().Finish();
  return millisecondsSince(start);
}

void Harness::scoreBlock(Method& reference, Method& method, const std::vector<Instance>& forest,
                         const Aabb& treeBounds, const Camera& camera, int width, int height,
                         int block, bool renderReference, ReferenceFrames& frames, int blocks,
                         InterleavedTimes& result) {
  // The block's scored frame: its first camera, untimed, read back from each (the reference's
  // from the cache once it holds them).
  if (renderReference) {
    DrawnStats drawn;
    frames.images.emplace_back(
        renderForestFrame(reference, forest, treeBounds, camera, width, height, &drawn),
        mSettings.flipPixelsPerDegree);
    frames.drawn.push_back(drawn);
  }
  const FlipReference& scored = frames.images[size_t(block)];
  const ImageRgba8& expected = scored.image();
  const DrawnStats& referenceDrawn = frames.drawn[size_t(block)];
  DrawnStats methodDrawn;
  const ImageRgba8 image =
      renderForestFrame(method, forest, treeBounds, camera, width, height, &methodDrawn);
  const ImageMetrics metrics = compareImages(scored, image);
  result.psnr += metrics.psnrFrame / blocks;
  result.flip += metrics.flip / blocks;
  result.coverageError += metrics.coverageErrorFrame / blocks;
  long covered = 0;
  for (size_t p = 3; p < expected.pixels.size(); p += 4) covered += expected.pixels[p] > 0;
  result.referenceCoverage += double(covered) / double(width * height) / blocks;
  result.drawn.counts += methodDrawn.counts;
  result.drawn.leafGeometryFraction += methodDrawn.leafGeometryFraction / blocks;
  result.referenceDrawn.counts += referenceDrawn.counts;
  result.referenceDrawn.leafGeometryFraction += referenceDrawn.leafGeometryFraction / blocks;
}

InterleavedTimes Harness::timeInterleaved(Method& reference, Method& method,
                                          const std::vector<Instance>& forest,
                                          const Aabb& treeBounds, const ForestTiming& timing,
                                          ReferenceFrames* cache) {
  const int width = timing.width, height = timing.height;
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest);
  const Aabb scene = forestBounds(forest, treeBounds);
  const float fov = mSettings.fovYDegrees;
  const auto camera = [&](int frame) {
    return forestPathCamera(timing, forest, treeBounds, frame, fov);
  };
  gl::api().Finish();
  for (int i = 0; i < timing.warmup; ++i) {
    timeFrame(reference, target, camera(i), width, height, scene);
    timeFrame(method, target, camera(i), width, height, scene);
  }
  InterleavedTimes result;
  int draws = 0;
  std::vector<double> referenceMs, methodMs;
  const int blocks = std::clamp(timing.blocks, 1, std::max(timing.frames, 1));
  ReferenceFrames local;
  ReferenceFrames& frames = cache && cache->complete(blocks) ? *cache : local;
  const bool renderReference = !(cache && cache->complete(blocks));
  std::vector<double> frameRatios;
  for (int block = 0; block < blocks; ++block) {
    const int first = block * timing.frames / blocks, last = (block + 1) * timing.frames / blocks;
    // Every camera is drawn by the reference and the method in turn, which going first
    // alternating (ABBA), so a hiccup or a drift in machine speed touches one pair of frames.
    std::vector<double> blockRatios;
    for (int i = first; i < last; ++i) {
      // A camera is drawn `repeats` times by each, more while the draws are too short to time
      // above the scheduler's noise, fewer once they are long; the fastest draw is its time.
      double ms[2] = {std::numeric_limits<double>::infinity(),
                      std::numeric_limits<double>::infinity()};  // [0] reference, [1] method
      double spent = 0.0;
      for (int repeat = 0;; ++repeat) {
        const bool enough = repeat >= timing.repeats && spent >= timing.minSampleMs;
        const bool tooLong = repeat >= 1 && spent >= timing.maxSampleMs;
        if (enough || tooLong || repeat >= 8 * timing.repeats) break;
        for (int turn = 0; turn < 2; ++turn) {
          const int which = (i + repeat) % 2 == 0 ? turn : 1 - turn;
          const double t =
              timeFrame(which == 0 ? reference : method, target, camera(i), width, height, scene);
          ms[which] = std::min(ms[which], t);
          spent += t;
        }
        ++draws;
      }
      referenceMs.push_back(ms[0]);
      methodMs.push_back(ms[1]);
      blockRatios.push_back(ms[0] / std::max(ms[1], 1e-9));
    }
    frameRatios.insert(frameRatios.end(), blockRatios.begin(), blockRatios.end());
    result.blockRatios.push_back(quantile(blockRatios, 0.5));
    scoreBlock(reference, method, forest, treeBounds, camera(first), width, height, block,
               renderReference, frames, blocks, result);
  }
  for (gl::DrawCounts* counts : {&result.drawn.counts, &result.referenceDrawn.counts}) {
    counts->primitives /= uint64_t(blocks);  // sums over the blocks → means
    counts->fragments /= uint64_t(blocks);
  }
  if (cache && renderReference) *cache = std::move(local);
  gl::checkError("Harness::timeInterleaved");
  result.reference = summarizeFrameTimes(referenceMs);
  result.method = summarizeFrameTimes(methodMs);
  result.repeats = double(draws) / double(std::max<size_t>(frameRatios.size(), 1));
  result.speedupMedian = quantile(frameRatios, 0.5);
  result.speedupQ25 = quantile(frameRatios, 0.25);
  result.speedupQ75 = quantile(frameRatios, 0.75);
  return result;
}

ImageRgba8 Harness::renderForestFrame(Method& method, const std::vector<Instance>& forest,
                                      const Aabb& treeBounds, const Camera& camera, int width,
                                      int height, DrawnStats* drawn) {
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest);
  drawFrame(method, target, makeFrame(camera, {width, height}, 1, mInstances.id()),
            forestBounds(forest, treeBounds), drawn);
  return display(readTarget(target));
}

}  // namespace canopy
