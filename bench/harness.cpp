#include "bench/harness.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
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

void Harness::uploadInstances(const std::vector<Instance>& instances, const Aabb& treeBounds) {
  if (mInstances.id() != 0 && instances.size() == mUploadedInstances.size() &&
      treeBounds.min == mInstanceBounds.min && treeBounds.max == mInstanceBounds.max &&
      std::equal(instances.begin(), instances.end(), mUploadedInstances.begin(),
                 [](const Instance& a, const Instance& b) {
                   return a.position == b.position && a.rotation == b.rotation &&
                          a.scale == b.scale;
                 })) {
    return;
  }
  std::vector<glm::mat4>& matrices = mInstanceMatrices;
  matrices.clear();
  mInstanceSpheres.clear();
  const float radius = 0.5f * glm::length(treeBounds.extent());
  for (const Instance& instance : instances) {
    const glm::mat4 model = instance.modelMatrix();
    matrices.push_back(model);
    mInstanceSpheres.emplace_back(glm::vec3(model * glm::vec4(treeBounds.center(), 1.0f)),
                                  radius * instance.scale);
  }
  gl::Device::OwnerScope owner(mDevice, "harness");
  mInstances = mDevice.createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER, matrices,
                                    "instance matrices");
  mUploadedInstances = instances;
  mInstanceBounds = treeBounds;
}

std::pair<std::span<const Instance>, GLuint> Harness::visibleInstances(
    const glm::mat4& viewProjection, const glm::vec3& viewer) {
  if (!mCulling) return {std::span<const Instance>(mUploadedInstances), mInstances.id()};
  // The frustum's six planes from the rows of the view-projection (Gribb and Hartmann), each
  // normalised so a sphere is outside when its centre lies more than its radius behind one.
  const glm::mat4 m = glm::transpose(viewProjection);
  std::array<glm::vec4, 6> planes = {m[3] + m[0], m[3] - m[0], m[3] + m[1],
                                     m[3] - m[1], m[3] + m[2], m[3] - m[2]};
  for (glm::vec4& plane : planes) plane /= std::max(glm::length(glm::vec3(plane)), 1e-20f);
  std::vector<std::pair<float, uint32_t>>& visible = mVisibleOrder;
  visible.clear();
  for (size_t i = 0; i < mUploadedInstances.size(); ++i) {
    const glm::vec4& sphere = mInstanceSpheres[i];
    const bool inside = std::all_of(planes.begin(), planes.end(), [&](const glm::vec4& plane) {
      return glm::dot(glm::vec3(plane), glm::vec3(sphere)) + plane.w >= -sphere.w;
    });
    if (inside) visible.emplace_back(glm::length(glm::vec3(sphere) - viewer), uint32_t(i));
  }
  // Nearest first, for every method alike: the depth test then rejects the fragments of trees
  // hidden behind nearer ones before their shaders run.
  std::stable_sort(visible.begin(), visible.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  mVisible.clear();
  mVisibleMatrices.clear();
  for (const auto& [distance, i] : visible) {
    mVisible.push_back(mUploadedInstances[i]);
    mVisibleMatrices.push_back(mInstanceMatrices[i]);
  }
  mVisibleBuffer.upload(mDevice, "harness", mVisibleMatrices, "visible instance matrices");
  return {std::span<const Instance>(mVisible), mVisibleBuffer.id()};
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

// Adds per-level instance counts into a running sum that may have fewer levels so far.
void addPerLevel(std::vector<uint64_t>& sum, const std::vector<uint64_t>& counts) {
  sum.resize(std::max(sum.size(), counts.size()), 0);
  for (size_t level = 0; level < counts.size(); ++level) sum[level] += counts[level];
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
  // Shadows are cast by every tree (the light's frustum holds the whole scene); the view draws
  // what its frustum holds.
  prepareShadows(method, frame, std::span(mUploadedInstances), scene);
  const auto [visible, buffer] =
      visibleInstances(frame.projection * frame.view, frame.cameraPosition);
  frame.instanceBuffer = buffer;
  beginFrame(target);
  method.draw(frame, visible);
  if (drawn) {
    drawn->counts = mStatistics->end();
    const double leaves = double(mTreeLeaves) * double(visible.size());
    drawn->leafGeometryFraction = leaves > 0 ? double(method.leafPolygonsDrawn()) / leaves : 0.0;
    drawn->instancesPerLevel = method.instancesPerLevel();
    drawn->woodInstancesPerLevel = method.woodInstancesPerLevel();
    drawn->instancesVisible = double(visible.size());
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
  uploadInstances({Instance{}}, mTreeBounds);
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

void Harness::scoreBlock(Method& method, const std::vector<Instance>& forest,
                         const Aabb& treeBounds, const Camera& camera, int width, int height,
                         int block, const ReferenceFrames& frames, int blocks,
                         InterleavedTimes& result) {
  // The block's scored frame: its first camera, untimed, read back from the method and compared
  // with the reference's.
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
  addPerLevel(result.drawn.instancesPerLevel, methodDrawn.instancesPerLevel);
  addPerLevel(result.drawn.woodInstancesPerLevel, methodDrawn.woodInstancesPerLevel);
  result.drawn.instancesVisible += methodDrawn.instancesVisible / blocks;
  result.referenceDrawn.instancesVisible += referenceDrawn.instancesVisible / blocks;
  result.referenceDrawn.counts += referenceDrawn.counts;
  result.referenceDrawn.leafGeometryFraction += referenceDrawn.leafGeometryFraction / blocks;
}

InterleavedTimes Harness::timeInterleaved(Method& reference, Method& method,
                                          const std::vector<Instance>& forest,
                                          const Aabb& treeBounds, const ForestTiming& timing,
                                          ReferenceFrames* cache) {
  Method* const methods[] = {&method};
  return std::move(timeInterleaved(reference, methods, forest, treeBounds, timing, cache)[0]);
}

namespace {

// One camera of one method: its fastest draw and the reference's beside it, and how long their
// draws took so far.
struct CameraSample {
  double ms[2] = {std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};  // [0] reference, [1] method
  double spent = 0.0;
  int pairs = 0;

  // A camera is drawn `repeats` times by each, more while the draws are too short to time above
  // the scheduler's noise, fewer once they are long.
  bool needsMore(const ForestTiming& timing) const {
    const bool enough = pairs >= timing.repeats && spent >= timing.minSampleMs;
    const bool tooLong = pairs >= 1 && spent >= timing.maxSampleMs;
    return !enough && !tooLong && pairs < 8 * timing.repeats;
  }
};

// One method's times and ratios from its cameras' samples: per frame, per block of frames
// [b · frames / blocks, (b + 1) · frames / blocks), and over the path.
InterleavedTimes summarizeSamples(const std::vector<CameraSample>& samples, int blocks) {
  InterleavedTimes result;
  const int frames = int(samples.size());
  std::vector<double> referenceMs, methodMs;
  int pairs = 0;
  for (int block = 0; block < blocks; ++block) {
    std::vector<double> blockRatios;
    for (int i = block * frames / blocks; i < (block + 1) * frames / blocks; ++i) {
      const CameraSample& sample = samples[size_t(i)];
      referenceMs.push_back(sample.ms[0]);
      methodMs.push_back(sample.ms[1]);
      blockRatios.push_back(sample.ms[0] / std::max(sample.ms[1], 1e-9));
      pairs += sample.pairs;
    }
    result.frameRatios.insert(result.frameRatios.end(), blockRatios.begin(), blockRatios.end());
    result.blockRatios.push_back(quantile(blockRatios, 0.5));
  }
  result.reference = summarizeFrameTimes(referenceMs);
  result.method = summarizeFrameTimes(methodMs);
  result.repeats = double(pairs) / double(std::max(frames, 1));
  double logSum = 0.0;
  for (const double ratio : result.frameRatios) logSum += std::log(ratio);
  result.speedup = std::exp(logSum / double(std::max<size_t>(result.frameRatios.size(), 1)));
  result.speedupQ25 = quantile(result.frameRatios, 0.25);
  result.speedupQ75 = quantile(result.frameRatios, 0.75);
  return result;
}

// The warm-up frames, then the timed passes over the path (timeInterleaved); `drawTimed` draws
// camera i with a method and returns its time in milliseconds.
std::vector<std::vector<CameraSample>> timePasses(
    Method& reference, std::span<Method* const> methods, const ForestTiming& timing,
    const std::function<double(Method&, int)>& drawTimed) {
  const size_t count = methods.size();
  for (int i = 0; i < timing.warmup; ++i) {
    drawTimed(reference, i);
    for (Method* method : methods) drawTimed(*method, i);
  }
  // Passes over the whole path: in each, every camera is drawn by the reference and each method
  // still short of samples in turn (ABBA: which goes first alternates, so a drift in machine
  // speed cancels within a pair). A method's draws of one camera are thus spread over the whole
  // timing of all methods, not taken back to back: this machine's speed changes in phases of
  // seconds that slow some shaders more than others, and a ratio measured inside one phase
  // carries it whole.
  std::vector<std::vector<CameraSample>> samples(count,
                                                 std::vector<CameraSample>(size_t(timing.frames)));
  for (int pass = 0;; ++pass) {
    bool drew = false;
    for (int i = 0; i < timing.frames; ++i) {
      for (size_t k = 0; k < count; ++k) {
        const size_t m = (k + size_t(i) + size_t(pass)) % count;  // no method always follows one
        CameraSample& sample = samples[m][size_t(i)];
        if (!sample.needsMore(timing)) continue;
        drew = true;
        for (int turn = 0; turn < 2; ++turn) {
          const int which = (i + sample.pairs) % 2 == 0 ? turn : 1 - turn;
          const double t = drawTimed(which == 0 ? reference : *methods[m], i);
          sample.ms[which] = std::min(sample.ms[which], t);
          sample.spent += t;
        }
        ++sample.pairs;
      }
    }
    if (!drew) break;
  }
  return samples;
}

}  // namespace

std::vector<InterleavedTimes> Harness::timeInterleaved(
    Method& reference, std::span<Method* const> methods, const std::vector<Instance>& forest,
    const Aabb& treeBounds, const ForestTiming& timing, ReferenceFrames* cache) {
  const int width = timing.width, height = timing.height;
  const size_t count = methods.size();
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest, treeBounds);
  const Aabb scene = forestBounds(forest, treeBounds);
  const float fov = mSettings.fovYDegrees;
  const auto camera = [&](int frame) {
    return forestPathCamera(timing, forest, treeBounds, frame, fov);
  };
  gl::api().Finish();
  const std::vector<std::vector<CameraSample>> samples =
      timePasses(reference, methods, timing, [&](Method& method, int frame) {
        return timeFrame(method, target, camera(frame), width, height, scene);
      });
  // The scored frames: each block's first camera, untimed (the reference's from the cache once
  // it holds them; they are the same for every method).
  const int blocks = std::clamp(timing.blocks, 1, std::max(timing.frames, 1));
  const auto firstOf = [&](int block) { return block * timing.frames / blocks; };
  ReferenceFrames local;
  const bool renderReference = !(cache && cache->complete(blocks));
  ReferenceFrames& frames = renderReference ? local : *cache;
  if (renderReference) {
    for (int block = 0; block < blocks; ++block) {
      DrawnStats drawn;
      frames.images.emplace_back(renderForestFrame(reference, forest, treeBounds,
                                                   camera(firstOf(block)), width, height, &drawn),
                                 mSettings.flipPixelsPerDegree);
      frames.drawn.push_back(drawn);
    }
  }
  std::vector<InterleavedTimes> results;
  results.reserve(count);
  for (size_t m = 0; m < count; ++m) {
    InterleavedTimes& result = results.emplace_back(summarizeSamples(samples[m], blocks));
    for (int block = 0; block < blocks; ++block) {
      scoreBlock(*methods[m], forest, treeBounds, camera(firstOf(block)), width, height, block,
                 frames, blocks, result);
    }
    for (gl::DrawCounts* counts : {&result.drawn.counts, &result.referenceDrawn.counts}) {
      counts->primitives /= uint64_t(blocks);  // sums over the blocks → means
      counts->fragments /= uint64_t(blocks);
    }
  }
  if (cache && renderReference) *cache = std::move(local);
  gl::checkError("Harness::timeInterleaved");
  return results;
}

ImageRgba8 Harness::renderForestFrame(Method& method, const std::vector<Instance>& forest,
                                      const Aabb& treeBounds, const Camera& camera, int width,
                                      int height, DrawnStats* drawn) {
  gl::RenderTarget& target = targetOfSize(width, height);
  uploadInstances(forest, treeBounds);
  drawFrame(method, target, makeFrame(camera, {width, height}, 1, mInstances.id()),
            forestBounds(forest, treeBounds), drawn);
  return display(readTarget(target));
}

}  // namespace canopy
