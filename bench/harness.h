#pragma once

#include <memory>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "common/config.h"
#include "common/flip.h"
#include "common/gl/device.h"
#include "common/gl/draw_statistics.h"
#include "common/image.h"
#include "common/metrics.h"
#include "common/views.h"
#include "methods/common/lod_instances.h"
#include "methods/method.h"

namespace canopy {

// How every image is made, for the reference and every method alike: the config's "views" keys
// (besides the rings). Each field is documented where visit() names it.
struct RenderSettings {
  int width = 512;
  int height = 512;
  int supersample = 2;
  float fovYDegrees = 40.0f;
  Shading shading = Shading::kUnlit;
  glm::vec3 background{0.5f, 0.6f, 0.75f};
  glm::vec3 lightDirection{0.3f, 0.8f, 0.5f};
  float ambient = 0.35f;
  bool ambientOcclusion = true;
  bool shadows = false;
  int shadowMapSize = 2048;
  double flipPixelsPerDegree = kFlipDefaultPixelsPerDegree;

  template <class V>
  void visit(V& v) {
    v("resolution", Resolution{width, height}, 16, 8192, "evaluation resolution of the views");
    v("supersample", supersample, 1, 8,
      "views are rendered at resolution × this per side and box-filtered down");
    v("fov_deg", fovYDegrees, 1.0f, 170.0f, "vertical field of view of the orbit rings");
    v("shading", shading, EnumNames<Shading>{{"unlit", Shading::kUnlit}, {"lit", Shading::kLit}},
      "albedo only, or two-sided Lambert with an ambient term");
    v("background", background, 0.0f, 1.0f, "sRGB colour every image is composited over");
    v("light_direction", lightDirection, -1.0f, 1.0f, "towards the light (normalised on use)");
    v("ambient", ambient, 0.0f, 1.0f, "share of the ambient term in lit shading");
    v("ambient_occlusion", ambientOcclusion,
      "lit: baked AO scales the ambient term, the reference's too (false: nobody's)");
    v("shadows", shadows, "lit: a shadow map rendered with the method itself each frame");
    v("shadow_map_size", shadowMapSize, 64, 16384, "shadow map texels per side");
    v("flip_ppd", flipPixelsPerDegree, 1.0, 1000.0,
      "FLIP's viewing condition in pixels per degree (the paper's 67)");
  }
};

struct FrameTimes {
  double medianMs = 0.0;
  double p95Ms = 0.0;
  double meanMs = 0.0;
  int frames = 0;
};

// What one frame drew: GL query counts and the share of the tree's leaves drawn as polygons.
struct DrawnStats {
  gl::DrawCounts counts;  // primitives and fragments of the whole frame (and shadows)
  double leafGeometryFraction =
      0.0;  // leaf polygons drawn / (leaves × instances); 0 without leaves
  std::vector<uint64_t> instancesPerLevel;      // Method::instancesPerLevel, summed over frames
  std::vector<uint64_t> woodInstancesPerLevel;  // Method::woodInstancesPerLevel, likewise
  double instancesVisible = 0.0;  // instances left after frustum culling (mean over frames)
};

// A forest timed along a camera path against the reference, and scored against it: the config's
// "forests" keys (besides the sizes and the camera path file).
struct ForestTiming {
  int frames = 60;
  int warmup = 10;
  int blocks = 5;
  // Defaults: one draw per camera (the protocol of the runs before repeats existed); the default
  // config asks for 2 with the limits below (results/README.md: how repeatable that is).
  int repeats = 1;             // draws of each camera by each; the fastest counts
  double minSampleMs = 0.0;    // short frames: repeated more, until a camera's draws span this
  double maxSampleMs = 1.0e5;  // slow frames: no repeat starts after a camera's draws span this
  int width = 512;
  int height = 512;
  std::vector<Camera> path;  // empty: the benchmark's orbit (forestCamera)

  template <class V>
  void visit(V& v) {
    v("frames", frames, 1, 100'000, "timed frames of each, the method and the reference");
    v("warmup", warmup, 0, 100'000, "untimed frames of each before");
    v("blocks", blocks, 1, 10'000,
      "the frames split into this many blocks, each timed reference/method in turn");
    v("repeats", repeats, 1, 1'000,
      "draws of each camera by the reference and the method in turn; a frame's time is the "
      "fastest, the one least disturbed by the rest of the machine");
    v("min_sample_ms", minSampleMs, 0.0, 100'000.0,
      "short frames are drawn more often (up to 8 × repeats) until a camera's draws span this");
    v("max_sample_ms", maxSampleMs, 0.0, 1'000'000.0,
      "no further repeat once a camera's draws span this (slow methods are drawn fewer times)");
    v("resolution", Resolution{width, height}, 16, 8192,
      "the forest frame (no supersampling; default: the views' resolution)");
  }
};

// Every camera of the path is drawn by the reference and the method in turn (ABBA: which goes
// first alternates per pair, so a drift in machine speed cancels), so every ratio compares frames
// timed moments apart; its repeats come in passes over the whole path, shared with every other
// method timed on the same forest, so they are spread over minutes. The frames are grouped in
// blocks; one untimed frame per block (its first camera) is read back from each and scored.
struct InterleavedTimes {
  FrameTimes reference, method;     // over all timed frames
  std::vector<double> blockRatios;  // per block: median of its per-frame ratios
  std::vector<double> frameRatios;  // per camera of the path: reference ms / method ms
  double repeats = 1.0;             // mean draws of a camera by each (the fastest counts)
  // The geometric mean of the per-frame ratios (reference ms / method ms): the mean of ratios
  // that treats a method 2× faster and 2× slower alike (Fleming & Wallace 1986), and it averages
  // every camera where a median of ratios that spread by view follows the one or two in the
  // middle (results/README.md measures both).
  double speedup = 0.0;
  double speedupQ25 = 0.0, speedupQ75 = 0.0;  // their quartiles
  double psnr = 0.0;                 // mean over the blocks' scored frames: whole-frame PSNR,
  double flip = 0.0;                 // FLIP,
  double coverageError = 0.0;        // mean |Δα| over the frame
  double referenceCoverage = 0.0;    // share of the frame the reference covers (α > 0)
  DrawnStats drawn, referenceDrawn;  // means over the scored frames
};

// The reference's scored frames of one forest along one timing (one per block), kept across the
// methods timed against it: they are the same for every method.
struct ReferenceFrames {
  std::vector<FlipReference> images;  // composited frames, prepared for FLIP
  std::vector<DrawnStats> drawn;
  bool complete(int blocks) const { return int(images.size()) == blocks; }
};

// Renders views and times forests for any method, through the same GL state and targets.
class Harness {
 public:
  Harness(gl::Device& device, RenderSettings settings);
  ~Harness();

  const RenderSettings& settings() const { return mSettings; }
  RenderSettings& settings() { return mSettings; }  // the viewer changes shading live
  // The single tree (at the origin): its bounds, which its shadow map must cover, and its leaf
  // count, the denominator of leaf_geometry_fraction.
  void setTree(const Aabb& bounds, size_t leaves);
  // The GL queries every counted frame uses; source() says which kind, for meta.json.
  gl::DrawStatistics& statistics();

  // The frame every draw gets: matrices for a target of outputSize · supersample pixels, level of
  // detail from the output size (FrameContext). For callers that draw into their own targets.
  FrameContext makeFrame(const Camera& camera, glm::ivec2 outputSize, int supersample,
                         GLuint instances) const;
  // Binds `target` and sets the GL state every method starts from.
  void beginFrame(const gl::RenderTarget& target);

  // One tree at the origin seen by `camera`: the render supersampled by settings().supersample,
  // box-filtered to width × height (linear, premultiplied; alpha is coverage). `drawn`, when
  // given, receives what the frame drew.
  ImageRgbaF renderLinearAt(Method& method, const Camera& camera, int width, int height,
                            DrawnStats* drawn = nullptr);
  ImageRgbaF renderLinear(Method& method, const Camera& camera);  // at the evaluation resolution
  // A linear premultiplied image composited over the background, 8-bit sRGB (alpha keeps
  // coverage): how every scored image is made, rendered or captured.
  ImageRgba8 display(const ImageRgbaF& linear) const;
  ImageRgba8 render(Method& method, const Camera& camera);  // display(renderLinear(...))

  // Times each of `methods` against `reference` on the same forest and cameras
  // (InterleavedTimes, one per method), all in one interleaved timing, at timing.width × height
  // without supersampling, glFinish after each frame. `cache`, when given, holds the reference's
  // scored frames: filled on first use, reused after.
  std::vector<InterleavedTimes> timeInterleaved(Method& reference, std::span<Method* const> methods,
                                                const std::vector<Instance>& forest,
                                                const Aabb& treeBounds, const ForestTiming& timing,
                                                ReferenceFrames* cache = nullptr);
  // One method alone against the reference.
  InterleavedTimes timeInterleaved(Method& reference, Method& method,
                                   const std::vector<Instance>& forest, const Aabb& treeBounds,
                                   const ForestTiming& timing, ReferenceFrames* cache = nullptr);

  // Frame `frame` of the forest path as an image (no supersampling), with what it drew.
  ImageRgba8 renderForestFrame(Method& method, const std::vector<Instance>& forest,
                               const Aabb& treeBounds, const Camera& camera, int width, int height,
                               DrawnStats* drawn = nullptr);

  // Lit and shadowed frames (settings().shadows): renders the method's depth from the light over
  // `scene` (LoD chosen from the viewer, as frame says, so close trees shadow with full
  // evaluation and far ones with their coarse levels) and fills the frame's shadow fields,
  // binding the map for the draw that follows. Does nothing for unlit frames.
  void prepareShadows(Method& method, FrameContext& frame, std::span<const Instance> instances,
                      const Aabb& scene);

  // Per-instance frustum culling and nearest-first order of every frame (on unless a test
  // compares against frames drawn without them).
  void setInstanceCulling(bool enabled) { mCulling = enabled; }

 private:
  gl::RenderTarget& targetOfSize(int width, int height);
  // Makes `instances` (each a tree with bounds `treeBounds`) the ones frames draw.
  void uploadInstances(const std::vector<Instance>& instances, const Aabb& treeBounds);
  // The instances whose bounding sphere meets the view frustum of `viewProjection`, nearest to
  // `viewer` first, and the buffer holding their matrices: every method, the reference
  // included, is handed only these (culling is part of the timed frame).
  std::pair<std::span<const Instance>, GLuint> visibleInstances(const glm::mat4& viewProjection,
                                                                const glm::vec3& viewer);
  // Shadows (if any), then the method's draw, into `target`; counted when `drawn` is given.
  void drawFrame(Method& method, const gl::RenderTarget& target, FrameContext frame,
                 const Aabb& scene, DrawnStats* drawn);
  ImageRgbaF readTarget(const gl::RenderTarget& target) const;
  double timeFrame(Method& method, const gl::RenderTarget& target, const Camera& camera, int width,
                   int height, const Aabb& scene);
  // Reads back and scores the method's frame of one block (timeInterleaved) against the
  // reference's, adding its share to the result's means.
  void scoreBlock(Method& method, const std::vector<Instance>& forest, const Aabb& treeBounds,
                  const Camera& camera, int width, int height, int block,
                  const ReferenceFrames& frames, int blocks, InterleavedTimes& result);

  gl::Device& mDevice;
  RenderSettings mSettings;
  std::vector<gl::RenderTarget> mTargets;
  gl::Buffer mInstances;
  std::vector<Instance> mUploadedInstances;
  Aabb mInstanceBounds;  // the bounds of the tree every uploaded instance is
  std::vector<glm::mat4> mInstanceMatrices;
  std::vector<glm::vec4> mInstanceSpheres;  // world centre and radius of each
  std::vector<Instance> mVisible;           // the last frame's culled instances and their matrices
  std::vector<glm::mat4> mVisibleMatrices;
  std::vector<std::pair<float, uint32_t>> mVisibleOrder;  // (distance, instance), reused
  StreamedMatrices mVisibleBuffer;
  bool mCulling = true;
  Aabb mTreeBounds;
  size_t mTreeLeaves = 0;
  gl::ShadowMap mShadowMap;
  std::unique_ptr<gl::DrawStatistics> mStatistics;  // made on first use (needs the context)
};

// The bounds of every instance of a tree with bounds `tree`.
Aabb forestBounds(const std::vector<Instance>& forest, const Aabb& tree);

// Median and 95th percentile (nearest rank) of frame times in milliseconds.
FrameTimes summarizeFrameTimes(std::vector<double> milliseconds);

// The q-quantile (0..1) of values by linear interpolation between order statistics.
double quantile(std::vector<double> values, double q);

// Frame i of a forest timing's camera path: the recorded path, or the orbit.
Camera forestPathCamera(const ForestTiming& timing, const std::vector<Instance>& forest,
                        const Aabb& treeBounds, int frame, float fovYDegrees);

}  // namespace canopy
