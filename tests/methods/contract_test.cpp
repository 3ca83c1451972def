// The contract every registered method meets: it bakes, uploads through the ledger (memory > 0),
// renders the tree where it is without GL errors, is deterministic, reports parameters that
// recreate it, and survives a save/load round trip with the same images.
#include <gtest/gtest.h>

#include "bench/harness.h"
#include "common/config.h"
#include "common/gl/api.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

class MethodContract : public testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    mContext = test::makeTestContext();
    mDevice = std::make_unique<gl::Device>(mLedger);
    RenderSettings settings;
    settings.width = settings.height = 96;
    settings.supersample = 2;
    mHarness = std::make_unique<Harness>(*mDevice, settings);
  }

  std::unique_ptr<Method> create(const nlohmann::json& params = nlohmann::json::object()) {
    return builtinMethods().find(GetParam()).create(params, "test");
  }

  // Parameters that keep a method's bake within a test's budget on the small tree; the contract
  // is the same at any size.
  static nlohmann::json quickParams(const std::string& method) {
    if (method == "volumetric_opacity")
      return {{"views", 8}, {"capture_resolution", 96}, {"level", 3}, {"max_iterations", 4}};
    return nlohmann::json::object();
  }

  // The method under test with `extra` parameters, or `other` (e.g. the reference) when given.
  std::unique_ptr<Method> bakeAndUpload(const Tree& tree, const std::string& owner,
                                        const std::string& other = "",
                                        const nlohmann::json& extra = nlohmann::json::object()) {
    nlohmann::json params = quickParams(GetParam());
    params.update(extra);
    auto method = other.empty()
                      ? create(params)
                      : builtinMethods().find(other).create(nlohmann::json::object(), "t");
    BakeContext context;
    context.seed = 11;
    // Image-based methods photograph the tree through the reference, as the runner does.
    context.photograph = [&](const Camera& camera, int width, int height) {
      if (!mPhotographer) {
        mPhotographer =
            builtinMethods().find("polygonal").create(nlohmann::json::object(), "reference");
        BakeContext referenceContext;
        mPhotographer->bake(tree, referenceContext);
        gl::Device::OwnerScope scope(*mDevice, "photographer");
        mPhotographer->upload(*mDevice);
      }
      return mHarness->renderLinearAt(*mPhotographer, camera, width, height);
    };
    method->bake(tree, context);
    gl::Device::OwnerScope scope(*mDevice, owner);
    method->upload(*mDevice);
    return method;
  }

  Camera camera(const Tree& tree, float elevation = 20.0f) const {
    return orbitCamera(tree.bounds, {3.0f, elevation, 30.0f}, 40.0f);
  }

  // Pixels with visible coverage: alpha of at least 8/255, so the faint fringe a blended,
  // bilinearly filtered impostor leaves around thin branches (volumetric_opacity) is not counted
  // as drawing outside the tree; alpha-tested methods are unaffected.
  static long coveredPixels(const ImageRgba8& image) {
    long covered = 0;
    for (size_t i = 3; i < image.pixels.size(); i += 4) covered += image.pixels[i] >= 8;
    return covered;
  }

  std::unique_ptr<gl::Context> mContext;
  gl::Ledger mLedger;
  std::unique_ptr<gl::Device> mDevice;
  std::unique_ptr<Harness> mHarness;
  std::unique_ptr<Method> mPhotographer;  // the polygonal tree that image-based methods photograph
};

// The reference's coverage of the same view, for comparison.
ImageRgba8 referenceImage(Harness& harness, gl::Device& device, const Tree& tree,
                          const Camera& camera) {
  auto reference = builtinMethods().find("polygonal").create(nlohmann::json::object(), "reference");
  BakeContext context;
  reference->bake(tree, context);
  gl::Device::OwnerScope scope(device, "reference");
  reference->upload(device);
  return harness.render(*reference, camera);
}

TEST_P(MethodContract, BakesUploadsThroughTheLedgerAndRendersTheTree) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "m");
  EXPECT_GT(mLedger.totals("m").total(), 0u);
  EXPECT_EQ(mLedger.totals("unowned").total(), 0u) << "every allocation has an owner";
  const ImageRgba8 image = mHarness->render(*method, camera(tree, 45.0f));
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
  // The method draws the tree where the reference does: a good share of its coverage, and
  // nothing far outside the reference's bounding box.
  const ImageRgba8 reference = referenceImage(*mHarness, *mDevice, tree, camera(tree, 45.0f));
  const long covered = coveredPixels(image), expected = coveredPixels(reference);
  ASSERT_GT(expected, 96 * 96 / 50);
  EXPECT_GT(covered, expected / 4)
      << "method " << covered << " px, reference " << expected << " px";
  EXPECT_LT(covered, expected * 2);
  int x0 = 96, y0 = 96, x1 = -1, y1 = -1;
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 96; ++x) {
      if (reference.at(x, y)[3] > 0)
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    }
  }
  long outside = 0;
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 96; ++x) {
      const bool inBox = x >= x0 - 4 && x <= x1 + 4 && y >= y0 - 4 && y <= y1 + 4;
      outside += image.at(x, y)[3] > 0 && !inBox;
    }
  }
  EXPECT_LT(outside, covered / 50 + 1);
  method.reset();
  EXPECT_EQ(mLedger.totals("m").total(), 0u) << "resources released with the method";
}

TEST_P(MethodContract, SameSeedGivesTheSameImages) {
  const Tree tree = test::smallTree();
  auto first = bakeAndUpload(tree, "a");
  auto second = bakeAndUpload(tree, "b");
  const ImageRgba8 a = mHarness->render(*first, camera(tree));
  EXPECT_EQ(a, mHarness->render(*first, camera(tree))) << "rendering twice";
  EXPECT_EQ(a, mHarness->render(*second, camera(tree))) << "baking twice";
}

// Pixels whose colour or alpha differ between two images of one size.
long differingPixels(const ImageRgba8& a, const ImageRgba8& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  long differing = 0;
  for (size_t i = 0; i + 4 <= std::min(a.pixels.size(), b.pixels.size()); i += 4)
    differing += !std::equal(&a.pixels[i], &a.pixels[i] + 4, &b.pixels[i]);
  return differing;
}

// `wood_first` only reorders the draws: the depth test keeps the same nearest surfaces, so the
// image is the same but for depth ties where a leaf stem meets its twig (under 0.5 % of pixels).
TEST_P(MethodContract, WoodFirstDrawsTheSameImage) {
  if (!create()->effectiveParams().contains("wood_first")) GTEST_SKIP() << "no wood_first";
  const Tree tree = test::smallTree();
  auto after = bakeAndUpload(tree, "after");
  auto first = bakeAndUpload(tree, "first", "", {{"wood_first", true}});
  for (const float elevation : {0.0f, 45.0f}) {
    const ImageRgba8 a = mHarness->render(*after, camera(tree, elevation));
    const long covered = coveredPixels(a);
    ASSERT_GT(covered, 96 * 96 / 50);
    EXPECT_LE(differingPixels(a, mHarness->render(*first, camera(tree, elevation))), covered / 200)
        << "elevation " << elevation;
  }
}

// `view_orders` only changes the order billboards are drawn in: every tree of a rotated forest,
// near (the finest cloud) to far, shows the same image as in the bake's order (but for depth ties
// between crossing billboards), and the orders take memory.
TEST_P(MethodContract, ViewOrdersDrawTheSameForest) {
  if (!create()->effectiveParams().contains("view_orders")) GTEST_SKIP() << "no view_orders";
  const Tree tree = test::smallTree();
  auto plain = bakeAndUpload(tree, "plain");
  auto ordered = bakeAndUpload(tree, "ordered", "", {{"view_orders", 8}});
  EXPECT_GT(mLedger.totals("ordered").geometry, mLedger.totals("plain").geometry);
  const std::vector<Instance> forest = layoutForest(9, tree.boundingSphereRadius(), 5);
  for (const int frame : {0, 3}) {
    const Camera view = forestCamera(forest, tree.bounds, frame, 8, 40.0f);
    const ImageRgba8 a = mHarness->renderForestFrame(*plain, forest, tree.bounds, view, 96, 96);
    const long covered = coveredPixels(a);
    ASSERT_GT(covered, 96 * 96 / 20) << "frame " << frame;
    EXPECT_LE(differingPixels(
                  a, mHarness->renderForestFrame(*ordered, forest, tree.bounds, view, 96, 96)),
              covered / 200)
        << "frame " << frame;
  }
}

TEST_P(MethodContract, EffectiveParamsRecreateTheMethod) {
  auto method = create();
  const nlohmann::json params = method->effectiveParams();
  ASSERT_TRUE(params.is_object());
  EXPECT_EQ(create(params)->effectiveParams(), params);
  EXPECT_THROW(create({{"no_such_parameter", 1}}), InputError);
}

TEST_P(MethodContract, SavedAssetLoadsAndRendersTheSame) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "original");
  test::TempDir dir;
  AssetFolder asset(dir.path());
  method->save(asset);
  EXPECT_GT(asset.sizeOnDisk(), 0u);
  auto loaded = create(method->effectiveParams());
  AssetFolder reader(dir.path());
  loaded->load(reader);
  {
    gl::Device::OwnerScope scope(*mDevice, "loaded");
    loaded->upload(*mDevice);
  }
  EXPECT_EQ(mLedger.totals("loaded").total(), mLedger.totals("original").total());
  // Another method's asset is bad input, not a crash.
  const std::string other = GetParam() == "polygonal" ? "billboard_cloud" : "polygonal";
  auto wrong = builtinMethods().find(other).create(nlohmann::json::object(), "test");
  AssetFolder again(dir.path());
  EXPECT_THROW(wrong->load(again), InputError);
  EXPECT_EQ(mHarness->render(*method, camera(tree, 60.0f)),
            mHarness->render(*loaded, camera(tree, 60.0f)));
}

// A corrupt asset header is bad input naming asset.json: each key removed, given the wrong type,
// or joined by a key no part reads.
TEST_P(MethodContract, CorruptAssetHeadersAreInputErrors) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "original");
  test::TempDir dir;
  AssetFolder asset(dir.path());
  method->save(asset);
  const std::string headerPath = (dir.path() / "asset.json").string();
  const nlohmann::json header = readJsonFile(headerPath);
  const auto expectInputError = [&](const nlohmann::json& corrupt, const std::string& what) {
    test::writeText(headerPath, corrupt.dump());
    auto loaded = create(method->effectiveParams());
    test::expectLoadErrorNamesTheFolder(*loaded, dir.path(), what);
  };
  for (const auto& [key, value] : header.items()) {
    nlohmann::json missing = header;
    missing.erase(key);
    expectInputError(missing, "without '" + key + "'");
    if (key == "params" || key == "report" || value.is_string()) continue;  // free-form
    nlohmann::json mistyped = header;
    mistyped[key] = "not this";
    expectInputError(mistyped, "'" + key + "' as a string");
  }
  nlohmann::json extra = header;
  extra["surprise"] = 1;
  expectInputError(extra, "an unknown key");
}

// Four 64² frames in two blocks: enough to exercise every part of the forest timing.
ForestTiming quickForestTiming(int warmup, int repeats) {
  ForestTiming timing;
  timing.frames = 4;
  timing.warmup = warmup;
  timing.blocks = 2;
  timing.repeats = repeats;
  timing.width = timing.height = 64;
  return timing;
}

TEST_P(MethodContract, DrawsForestsWithoutGlErrors) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "m");
  auto reference = bakeAndUpload(tree, "reference", "polygonal");
  mHarness->setTree(tree.bounds, tree.leaves.size());
  const auto forest = layoutForest(9, tree.boundingSphereRadius(), 3);
  const ForestTiming timing = quickForestTiming(1, 1);
  const InterleavedTimes times =
      mHarness->timeInterleaved(*reference, *method, forest, tree.bounds, timing);
  EXPECT_EQ(times.method.frames, 4);
  EXPECT_EQ(times.reference.frames, 4);
  EXPECT_GT(times.method.medianMs, 0.0);
  EXPECT_EQ(times.blockRatios.size(), 2u);
  EXPECT_GT(times.speedup, 0.0);
  EXPECT_GT(times.referenceCoverage, 0.0);
  EXPECT_GT(times.drawn.counts.primitives, 0u);
  EXPECT_GE(times.flip, 0.0);
  EXPECT_LE(times.flip, 1.0);
  const Camera camera = forestCamera(forest, tree.bounds, 0, 3, 40.0f);
  const ImageRgba8 frame =
      mHarness->renderForestFrame(*method, forest, tree.bounds, camera, 96, 96);
  EXPECT_GT(coveredPixels(frame), 0);
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// The harness culls instances by their bounding spheres against the frustum: from inside a
// forest, half of it behind the camera, a frame is the same with and without culling, and the
// trees behind are not handed to the method.
TEST_P(MethodContract, CullingDropsOnlyTreesTheFrameDoesNotShow) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "m");
  mHarness->setTree(tree.bounds, tree.leaves.size());
  const float radius = tree.boundingSphereRadius();
  const auto forest = layoutForest(36, radius, 11);
  Camera camera;
  camera.position = {0.0f, tree.bounds.center().y, 0.3f * radius};
  camera.target = camera.position + glm::vec3(1.0f, -0.1f, 0.4f);
  camera.farPlane = 40.0f * radius;
  DrawnStats culled, all;
  const ImageRgba8 withCulling =
      mHarness->renderForestFrame(*method, forest, tree.bounds, camera, 96, 96, &culled);
  mHarness->setInstanceCulling(false);
  const ImageRgba8 without =
      mHarness->renderForestFrame(*method, forest, tree.bounds, camera, 96, 96, &all);
  mHarness->setInstanceCulling(true);
  EXPECT_GT(coveredPixels(withCulling), 96 * 96 / 10);
  EXPECT_EQ(withCulling, without);
  EXPECT_EQ(all.instancesVisible, 36.0);
  EXPECT_GT(culled.instancesVisible, 3.0);
  EXPECT_LT(culled.instancesVisible, 26.0) << "about half the forest is behind the camera";
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// Timing several methods at once (how the runner times a tree's variants) gives each the scores
// and draw counts it gets alone, and every camera the repeats asked for: the shared passes only
// change when the draws happen, never what is drawn or whose result is whose.
TEST_P(MethodContract, TimedWithOtherMethodsScoresAsWhenTimedAlone) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "m");
  auto reference = bakeAndUpload(tree, "reference", "polygonal");
  auto other = bakeAndUpload(tree, "other", "polygonal");
  mHarness->setTree(tree.bounds, tree.leaves.size());
  const auto forest = layoutForest(4, tree.boundingSphereRadius(), 5);
  const ForestTiming timing = quickForestTiming(0, 2);
  const InterleavedTimes alone =
      mHarness->timeInterleaved(*reference, *method, forest, tree.bounds, timing);
  Method* const both[] = {other.get(), method.get()};
  const std::vector<InterleavedTimes> together =
      mHarness->timeInterleaved(*reference, both, forest, tree.bounds, timing);
  ASSERT_EQ(together.size(), 2u);
  const InterleavedTimes& shared = together[1];
  EXPECT_EQ(shared.psnr, alone.psnr);
  EXPECT_EQ(shared.flip, alone.flip);
  EXPECT_EQ(shared.coverageError, alone.coverageError);
  EXPECT_EQ(shared.drawn.counts.primitives, alone.drawn.counts.primitives);
  EXPECT_EQ(shared.drawn.counts.fragments, alone.drawn.counts.fragments);
  EXPECT_EQ(shared.drawn.leafGeometryFraction, alone.drawn.leafGeometryFraction);
  EXPECT_EQ(shared.blockRatios.size(), 2u);
  EXPECT_EQ(shared.method.frames, 4);
  EXPECT_DOUBLE_EQ(shared.repeats, 2.0);
  EXPECT_DOUBLE_EQ(alone.repeats, 2.0);
  // The other method's result is its own, not a copy of this one's.
  if (GetParam() != "polygonal") {
    EXPECT_NE(together[0].drawn.counts.primitives, shared.drawn.counts.primitives);
  }
}

// The fair-harness rule: level of detail follows the output image, not the supersampled target,
// so the same view at supersample 1 and 2 draws the same primitives (counted by GL queries) and
// the same share of leaves as polygons; only the filtering differs. Views from near to far, so
// every level of every method is crossed.
TEST_P(MethodContract, LevelOfDetailDoesNotDependOnSupersampling) {
  const Tree tree = test::smallTree();
  auto method = bakeAndUpload(tree, "m");
  mHarness->setTree(tree.bounds, tree.leaves.size());
  for (const float distance : {1.5f, 3.0f, 8.0f, 24.0f, 60.0f}) {
    const Camera camera = orbitCamera(tree.bounds, {distance, 30.0f, 30.0f}, 40.0f);
    DrawnStats drawn[2];
    for (int s : {1, 2}) {
      mHarness->settings().supersample = s;
      mHarness->renderLinearAt(*method, camera, 96, 96, &drawn[s - 1]);
    }
    EXPECT_GT(drawn[0].counts.primitives, 0u) << distance;
    EXPECT_EQ(drawn[0].counts.primitives, drawn[1].counts.primitives) << "distance " << distance;
    EXPECT_EQ(drawn[0].leafGeometryFraction, drawn[1].leafGeometryFraction)
        << "distance " << distance;
  }
  mHarness->settings().supersample = 2;
}

INSTANTIATE_TEST_SUITE_P(EveryRegisteredMethod, MethodContract,
                         testing::ValuesIn(builtinMethods().names()),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

TEST(Harness, FrameTimeStatistics) {
  const FrameTimes times =
      summarizeFrameTimes({5, 1, 3, 2, 4, 100, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19});
  EXPECT_DOUBLE_EQ(times.medianMs, 10.5);  // even count: mean of the two middle values
  EXPECT_DOUBLE_EQ(times.p95Ms, 19.0);     // nearest rank: ceil(0.95·20) = 19th of 20
  EXPECT_EQ(times.frames, 20);
}

}  // namespace
}  // namespace canopy
