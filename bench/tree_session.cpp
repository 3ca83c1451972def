#include "bench/tree_session.h"

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "common/captures.h"
#include "common/gl/api.h"
#include "common/system_info.h"

namespace canopy {
namespace {

std::string poseKey(const ViewPose& pose) {
  return fmt::format("d{:g}_e{:g}_a{:g}", pose.distance, pose.elevation, pose.azimuth);
}

void addRing(std::vector<EvalView>& views, const Tree& tree, const char* ring,
             const std::string& keyPrefix, const std::vector<ViewPose>& poses, float fov,
             const RenderSettings& render) {
  for (const ViewPose& pose : poses) {
    EvalView view;
    view.key = keyPrefix + poseKey(pose);
    view.camera = orbitCamera(tree.bounds, pose, fov);
    view.width = render.width;
    view.height = render.height;
    view.ring = ring;
    view.distance = pose.distance;
    view.elevation = pose.elevation;
    view.azimuth = pose.azimuth;
    views.push_back(std::move(view));
  }
}

}  // namespace

std::vector<EvalView> evaluationViews(const Tree& tree, const ViewSettings& settings) {
  std::vector<EvalView> views;
  const RenderSettings& render = settings.render;
  if (tree.captures) {
    const float radius = tree.boundingSphereRadius();
    for (const CapturedView& v : tree.captures->test) {
      EvalView view;
      view.key = "test_" + std::filesystem::path(v.name).stem().string();
      view.camera = v.camera;
      view.width = v.image.width;
      view.height = v.image.height;
      view.ring = "capture";
      view.distance =
          std::round(10.0 * glm::length(v.camera.position - tree.bounds.center()) / radius) / 10.0;
      view.captureView = v.name;
      view.captured = &v.image;
      views.push_back(std::move(view));
    }
    return views;
  }
  addRing(views, tree, "orbit", "",
          makeViewRings(settings.distances, settings.elevations, settings.azimuths),
          render.fovYDegrees, render);
  const CloseupSettings& closeups = settings.closeups;
  if (closeups.enabled) {
    addRing(views, tree, "closeup", "closeup_",
            makeViewRings({closeups.distance}, closeups.elevations, closeups.azimuths),
            closeups.fovYDegrees, render);
  }
  return views;
}

BakedMethod bakeMethod(const MethodVariant& variant, const Tree& tree, gl::Device& device,
                       BakeContext context,
                       const std::optional<std::filesystem::path>& assetFolder) {
  using Clock = std::chrono::steady_clock;
  BakedMethod baked;
  baked.method =
      builtinMethods().find(variant.method).create(variant.params, "methods." + variant.label);
  const bool peakReset = resetPeakRss();
  const auto start = Clock::now();
  baked.method->bake(tree, context);
  const double bakeSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  const uint64_t peak = peakRssBytes();
  {
    gl::Device::OwnerScope owner(device, variant.label);
    baked.method->upload(device);
  }
  gl::checkError(("upload of " + variant.label).c_str());
  BakeRecord& record = baked.record;
  if (assetFolder) {
    std::filesystem::remove_all(*assetFolder);
    std::filesystem::create_directories(*assetFolder);
    AssetFolder asset(*assetFolder);
    baked.method->save(asset);
    record.diskBytes = asset.sizeOnDisk();
  }
  const gl::MemoryTotals memory = device.ledger().totals(variant.label);
  record.method = variant.method;
  record.variant = variant.label;
  record.bakeSeconds = bakeSeconds;
  record.bakePeakRssBytes = peak;
  record.bakePeakRssScope = peakReset ? "bake" : "process";
  record.memory = {memory.texture, memory.geometry, memory.other, memory.total()};
  record.params = baked.method->effectiveParams();
  record.report = baked.method->bakeReport();
  return baked;
}

TreeSession::TreeSession(Tree tree, std::string label, const ExperimentConfig& config,
                         gl::Device& device, Harness& harness)
    : mTree(std::move(tree)),
      mLabel(std::move(label)),
      mConfig(config),
      mDevice(device),
      mHarness(harness),
      mViews(evaluationViews(mTree, config.views)) {
  mHarness.setTree(mTree.bounds, mTree.leaves.size());
}

BakeContext TreeSession::bakeContext() {
  BakeContext context;
  context.seed = mConfig.seed;
  context.shading = mConfig.views.render.shading;
  context.ambientOcclusion = mConfig.views.render.ambientOcclusion;
  context.photograph = [this](const Camera& camera, int width, int height) {
    return photograph(camera, width, height);
  };
  return context;
}

Method* TreeSession::reference() {
  if (!hasMesh()) return nullptr;
  if (!mReference) {
    // Its own ledger owner: the reference's memory is not the polygonal variant's.
    const MethodVariant variant{"polygonal", nlohmann::json::object(), "reference"};
    BakeContext context = bakeContext();
    context.photograph = nullptr;  // the reference photographs nothing
    mReference = bakeMethod(variant, mTree, mDevice, context, std::nullopt);
  }
  return mReference->method.get();
}

const FlipReference& TreeSession::scoredReference(const EvalView& view) {
  auto it = mReferenceImages.find(view.key);
  if (it == mReferenceImages.end()) {
    const ImageRgba8 image = view.captured
                                 ? mHarness.display(*view.captured)
                                 : mHarness.display(mHarness.renderLinearAt(
                                       *reference(), view.camera, view.width, view.height));
    if (mImageFolder) {
      writePng(*mImageFolder / safeName(mLabel) / "reference" / (view.key + ".png"),
               withOpaqueAlpha(image));
    }
    it = mReferenceImages
             .emplace(view.key, FlipReference(image, mConfig.views.render.flipPixelsPerDegree))
             .first;
  }
  return it->second;
}

ImageRgbaF TreeSession::photograph(const Camera& camera, int width, int height) {
  return mHarness.renderLinearAt(*reference(), camera, width, height);
}

const std::vector<ImageRgba8>& TreeSession::referencePath(const std::string& name,
                                                          const std::vector<PathFrame>& path,
                                                          int width, int height) {
  auto [it, inserted] = mReferencePaths.try_emplace(name);
  if (inserted) {
    std::vector<uint64_t> ignored;
    it->second = renderPath(mHarness, *reference(), path, width, height, ignored);
  }
  return it->second;
}

std::vector<Instance> TreeSession::forest(int size) const {
  return layoutForest(size, mTree.boundingSphereRadius(), mConfig.seed);
}

}  // namespace canopy
