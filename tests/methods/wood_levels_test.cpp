// The wood's levels of detail (methods/common/wood_levels): simplified by meshoptimizer within
// doubling error bounds, thin branches vanish before the trunk does, and the LoD thresholds
// keep every instance's wood error within the requested output pixels.
#include <gtest/gtest.h>

#include <algorithm>

#include <glm/gtc/constants.hpp>

#include "methods/common/lod_instances.h"
#include "methods/common/wood_levels.h"

namespace canopy {
namespace {

// A closed tube along y: `sides` around, `rings` along, capped, appended to the mesh.
void addTube(std::vector<glm::vec3>& positions, std::vector<uint32_t>& indices, glm::vec3 base,
             float radius, float height, int sides, int rings) {
  const auto first = uint32_t(positions.size());
  for (int r = 0; r <= rings; ++r) {
    for (int s = 0; s < sides; ++s) {
      const float a = glm::two_pi<float>() * float(s) / float(sides);
      positions.push_back(base + glm::vec3(radius * std::cos(a), height * float(r) / float(rings),
                                           radius * std::sin(a)));
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < sides; ++s) {
      const uint32_t a = first + uint32_t(r * sides + s),
                     b = first + uint32_t(r * sides + (s + 1) % sides);
      const uint32_t c = a + uint32_t(sides), d = b + uint32_t(sides);
      indices.insert(indices.end(), {a, c, b, b, c, d});
    }
  }
  for (int end = 0; end <= 1; ++end) {  // fans closing both ends
    const auto centre = uint32_t(positions.size());
    positions.push_back(base + glm::vec3(0.0f, end ? height : 0.0f, 0.0f));
    const uint32_t ring = first + uint32_t(end ? rings * sides : 0);
    for (int s = 0; s < sides; ++s) {
      const uint32_t a = ring + uint32_t(s), b = ring + uint32_t((s + 1) % sides);
      if (end)
        indices.insert(indices.end(), {centre, b, a});
      else
        indices.insert(indices.end(), {centre, a, b});
    }
  }
}

struct TwoTubes {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  uint32_t trunkVertices = 0;  // vertices below this index belong to the trunk
};

// A trunk of radius 0.1 and a twig of radius 0.004 beside it, each one material.
TwoTubes trunkAndTwig() {
  TwoTubes mesh;
  addTube(mesh.positions, mesh.indices, {0, 0, 0}, 0.1f, 2.0f, 24, 40);
  mesh.trunkVertices = uint32_t(mesh.positions.size());
  addTube(mesh.positions, mesh.indices, {0.5f, 0.5f, 0}, 0.004f, 1.0f, 8, 30);
  return mesh;
}

// Triangles of `level` with a corner at or above vertex `firstVertex` / below it.
std::pair<size_t, size_t> trianglesOf(const WoodLevels& levels, size_t level,
                                      uint32_t firstVertex) {
  size_t below = 0, above = 0;
  const size_t begin = levels.firstRange(level);
  for (size_t r = begin; r < begin + levels.rangesPerLevel[level]; ++r) {
    const WoodRange& range = levels.ranges[r];
    for (uint32_t i = range.first; i < range.first + range.count; i += 3)
      (levels.indices[i] >= firstVertex ? above : below) += 1;
  }
  return {below, above};
}

TEST(WoodLevels, FewerTrianglesPerLevelWithinDoublingBounds) {
  const TwoTubes mesh = trunkAndTwig();
  const std::vector<WoodRange> ranges = {{0, uint32_t(mesh.indices.size()), 0}};
  const WoodLevels levels = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.001f, 0.5f);
  ASSERT_TRUE(levels.consistent());
  ASSERT_GE(levels.levels(), 3u);
  EXPECT_EQ(levels.triangles(0), mesh.indices.size() / 3) << "level 0 is the full mesh";
  EXPECT_EQ(levels.errors[0], 0.0f);
  for (size_t l = 1; l < levels.levels(); ++l) {
    // Each kept level removes at least a sixth of the one before (the rest are skipped).
    EXPECT_LE(uint64_t(levels.triangles(l)) * 6, uint64_t(levels.triangles(l - 1)) * 5) << l;
    EXPECT_GT(levels.errors[l], levels.errors[l - 1]);
    EXPECT_LE(levels.errors[l], 0.5f * 1.0001f);
    // Every simplified vertex is a vertex of the full mesh (neither simplifier invents one); a
    // level may have no ranges at all once the whole wood vanished within its bound.
    const size_t begin = levels.firstRange(l);
    for (size_t r = begin; r < begin + levels.rangesPerLevel[l]; ++r) {
      const WoodRange& range = levels.ranges[r];
      for (uint32_t k = range.first; k < range.first + range.count; ++k)
        EXPECT_LT(levels.indices[k], mesh.positions.size());
    }
  }
}

TEST(WoodLevels, ThinBranchesVanishBeforeTheTrunk) {
  const TwoTubes mesh = trunkAndTwig();
  const std::vector<WoodRange> ranges = {{0, uint32_t(mesh.indices.size()), 0}};
  const WoodLevels levels = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.001f, 0.5f);
  bool twigGone = false;
  for (size_t l = 0; l < levels.levels(); ++l) {
    const auto [trunk, twig] = trianglesOf(levels, l, mesh.trunkVertices);
    // Within a bound below half the trunk's radius the trunk keeps a body.
    if (levels.errors[l] < 0.05f) {
      EXPECT_GE(trunk, 8u) << "level " << l;
    }
    // A bound several times the twig's radius (0.004) lets it collapse away.
    if (levels.errors[l] >= 0.032f) {
      EXPECT_EQ(twig, 0u) << "level " << l;
    }
    if (levels.errors[l] <= 0.002f) {
      EXPECT_GT(twig, 0u) << "level " << l;
    }
    twigGone = twigGone || twig == 0;
  }
  EXPECT_TRUE(twigGone);
}

TEST(WoodLevels, ThresholdsKeepTheErrorWithinThePixels) {
  const TwoTubes mesh = trunkAndTwig();
  const std::vector<WoodRange> ranges = {{0, uint32_t(mesh.indices.size()), 0}};
  const WoodLevels levels = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.001f, 0.5f);
  const float treeRadius = 1.2f, errorPixels = 0.75f;
  const std::vector<float> thresholds = levels.thresholds(treeRadius, errorPixels);
  ASSERT_EQ(thresholds.size(), levels.levels() - 1);
  for (float radiusPixels = 0.5f; radiusPixels < 5000.0f; radiusPixels *= 1.17f) {
    const int level = LodInstances::levelFor(radiusPixels, thresholds);
    ASSERT_LT(size_t(level), levels.levels());
    // The chosen level's error, in output pixels, is within the bound ...
    EXPECT_LE(levels.errors[size_t(level)] * radiusPixels / treeRadius, errorPixels * 1.0001f)
        << radiusPixels;
    // ... and the next coarser one would exceed it.
    if (size_t(level) + 1 < levels.levels()) {
      EXPECT_GT(levels.errors[size_t(level) + 1] * radiusPixels / treeRadius, errorPixels)
          << radiusPixels;
    }
  }
  EXPECT_TRUE(levels.thresholds(treeRadius, 0.0f).empty()) << "0 px: the full mesh always";
}

// Residual chains (the wood a method's images do not hold): above the first chain's radius the
// full chain within the pixel bound, below it that residual chain within the same bound, and
// below the second chain's radius (images that hold more of the wood: a far cloud) the second,
// never a level of another chain.
TEST(WoodLevels, ResidualChainsTakeOverBelowTheirRadii) {
  const TwoTubes mesh = trunkAndTwig();
  const std::vector<WoodRange> ranges = {{0, uint32_t(mesh.indices.size()), 0}};
  WoodLevels levels = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.001f, 0.5f);
  const size_t fullLevels = levels.levels();
  // The first residual: the trunk alone (the twig held by the images).
  std::vector<bool> captured(mesh.positions.size(), false);
  for (size_t v = mesh.trunkVertices; v < captured.size(); ++v) captured[v] = true;
  const WoodLevels residual = residualLevels(levels, captured);
  ASSERT_EQ(residual.levels(), fullLevels);
  EXPECT_EQ(residual.errors, levels.errors) << "the full chain's simplification, its bounds";
  uint32_t trunkTriangles = 0;
  for (size_t i = 0; i < mesh.indices.size(); i += 3)
    trunkTriangles += mesh.indices[i] < mesh.trunkVertices;
  for (size_t level = 0; level < residual.levels(); ++level) {
    EXPECT_LE(residual.triangles(level), levels.triangles(level));
    for (size_t r = residual.firstRange(level);
         r < residual.firstRange(level) + residual.rangesPerLevel[level]; ++r) {
      for (uint32_t i = residual.ranges[r].first;
           i < residual.ranges[r].first + residual.ranges[r].count; ++i)
        ASSERT_LT(residual.indices[i], mesh.trunkVertices) << "no twig triangle at " << level;
    }
  }
  // The second: nothing left (the images of the smallest trees hold all the wood).
  const WoodLevels nothing = residualLevels(levels, std::vector<bool>(captured.size(), true));
  ASSERT_EQ(nothing.levels(), fullLevels);
  EXPECT_TRUE(nothing.indices.empty());
  const float below = 40.0f, farBelow = 12.0f;
  appendResidualLevels(levels, residual, below);
  ASSERT_TRUE(levels.consistent());
  appendResidualLevels(levels, nothing, farBelow);
  ASSERT_TRUE(levels.consistent());
  ASSERT_EQ(levels.residualChains.size(), 2u);
  ASSERT_EQ(levels.residualChains[0].from, fullLevels);
  ASSERT_EQ(levels.residualChains[1].from, 2 * fullLevels);
  EXPECT_EQ(levels.triangles(fullLevels), trunkTriangles);
  EXPECT_EQ(levels.triangles(2 * fullLevels), 0u);
  const float treeRadius = 1.2f;
  for (const float errorPixels : {0.0f, 0.3f, 2.0f}) {
    const std::vector<float> thresholds = levels.thresholds(treeRadius, errorPixels);
    ASSERT_EQ(thresholds.size(), levels.levels() - 1);
    EXPECT_TRUE(std::is_sorted(thresholds.rbegin(), thresholds.rend())) << "decreasing";
    for (float radiusPixels = 0.5f; radiusPixels < 5000.0f; radiusPixels *= 1.17f) {
      const auto level = size_t(LodInstances::levelFor(radiusPixels, thresholds));
      ASSERT_LT(level, levels.levels());
      const size_t chain = radiusPixels < farBelow ? 2 : radiusPixels < below ? 1 : 0;
      EXPECT_EQ(level / fullLevels, chain) << radiusPixels << " px";
      EXPECT_EQ(levels.isResidual(level), chain > 0) << radiusPixels;
      EXPECT_LE(levels.errors[level] * radiusPixels / treeRadius, errorPixels * 1.0001f)
          << radiusPixels << " px, bound " << errorPixels;
    }
  }
  WoodLevels corrupt = levels;
  corrupt.residualChains.back().from = levels.levels();
  EXPECT_FALSE(corrupt.consistent());
  corrupt = levels;
  corrupt.residualChains.front().belowPixels = 0.0f;
  EXPECT_FALSE(corrupt.consistent());
  corrupt = levels;
  corrupt.residualChains.back().belowPixels = below;
  EXPECT_FALSE(corrupt.consistent()) << "each chain below the one before";
}

TEST(WoodLevels, MaterialsStaySeparateAndNoBoundMeansOneLevel) {
  TwoTubes mesh = trunkAndTwig();
  const auto split = uint32_t(mesh.indices.size() / 2 / 3 * 3);
  const std::vector<WoodRange> ranges = {{0, split, 0},
                                         {split, uint32_t(mesh.indices.size()) - split, 1}};
  const WoodLevels levels = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.001f, 0.5f);
  ASSERT_TRUE(levels.consistent());
  for (size_t l = 0; l < levels.levels(); ++l) {
    const size_t begin = levels.firstRange(l);
    for (size_t r = begin + 1; r < begin + levels.rangesPerLevel[l]; ++r)
      EXPECT_LT(levels.ranges[r - 1].material, levels.ranges[r].material) << "one range each";
  }
  const WoodLevels single = buildWoodLevels(mesh.positions, mesh.indices, ranges, 0.0f, 0.5f);
  EXPECT_EQ(single.levels(), 1u);
  EXPECT_EQ(single.indices, mesh.indices);
  WoodLevels corrupt = levels;
  corrupt.ranges.back().count += 3;
  EXPECT_FALSE(corrupt.consistent());
  corrupt = levels;
  corrupt.errors.back() = std::nanf("");
  EXPECT_FALSE(corrupt.consistent());
}

}  // namespace
}  // namespace canopy

#include "bench/harness.h"
#include "common/metrics.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

// A GL context, a 128² harness and the small L-system tree the wood tests draw.
class WoodInImpostors : public testing::Test {
 protected:
  WoodInImpostors() { harness.setTree(tree.bounds, tree.leaves.size()); }
  // Draws `method` from `distance` bounding radii (elevation 10°) at 128², composited over grey.
  std::pair<DrawnStats, ImageRgba8> drawAt(Method& method, float distance) {
    DrawnStats stats;
    const Camera camera = orbitCamera(tree.bounds, {distance, 10.0f, 0.0f}, 40.0f);
    const ImageRgbaF image = harness.renderLinearAt(method, camera, 128, 128, &stats);
    return {stats, compositeToSrgb8(image, glm::vec3(0.5f))};
  }
  static RenderSettings settings128() {
    RenderSettings settings;
    settings.width = settings.height = 128;
    return settings;
  }
  std::unique_ptr<gl::Context> context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device{ledger};
  const Tree tree = test::smallTree(400, 3);
  Harness harness{device, settings128()};
};

// The wood levels inside an impostor: a far tree draws far fewer wood triangles than with the
// full mesh, and at a bound below a pixel a near view is the full mesh's, pixel for pixel.
TEST_F(WoodInImpostors, FarTreesDrawCoarseWoodAndNearViewsTheFullMesh) {
  // One chain of levels: no wood captured into the images (CapturedWood checks that).
  const auto withError = [](double pixels) {
    return nlohmann::json{
        {"wood_error_px", pixels}, {"wood_capture_px", 0.0}, {"wood_capture_far_px", 0.0}};
  };
  auto full = test::bakeAndUpload(device, tree, "billboard_cloud", withError(0.0));
  auto coarse = test::bakeAndUpload(device, tree, "billboard_cloud", withError(1.0),
                                    Shading::kUnlit, "coarse");
  const nlohmann::json levels = coarse->bakeReport().at("wood_levels");
  ASSERT_GE(levels.size(), 3u);
  EXPECT_EQ(full->bakeReport().at("wood_levels").size(), 1u);
  const auto draw = [&](Method& method, float distance) {
    DrawnStats drawn;
    const Camera camera = orbitCamera(tree.bounds, {distance, 10.0f, 0.0f}, 40.0f);
    const ImageRgbaF image = harness.renderLinearAt(method, camera, 128, 128, &drawn);
    return std::make_pair(drawn, image);
  };
  const auto [fullFar, fullFarImage] = draw(*full, 30.0f);
  const auto [coarseFar, coarseFarImage] = draw(*coarse, 30.0f);
  const uint64_t woodTriangles = levels[0].at("triangles").get<uint64_t>();
  EXPECT_LT(coarseFar.counts.primitives + woodTriangles / 2, fullFar.counts.primitives)
      << "a tree of 6 px radius drops at least half its wood";
  ASSERT_EQ(coarseFar.woodInstancesPerLevel.size(), levels.size());
  EXPECT_EQ(coarseFar.woodInstancesPerLevel[0], 0u);
  // Near (1.2 radii, ~260 px of radius): a bound of 0.1 px keeps the full mesh.
  auto fine =
      test::bakeAndUpload(device, tree, "billboard_cloud", withError(0.1), Shading::kUnlit, "fine");
  const auto [fullNear, fullNearImage] = draw(*full, 1.2f);
  const auto [fineNear, fineNearImage] = draw(*fine, 1.2f);
  EXPECT_EQ(fineNear.woodInstancesPerLevel.at(0), 1u);
  EXPECT_EQ(fineNearImage.pixels, fullNearImage.pixels);
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// Wood captured into the images of the clouds drawn as images only (wood_capture_px): the
// classic cloud's middle and far clouds, the multi-layer far cloud's low-resolution texture. A
// tree drawn with those clouds draws only the residual wood, keeps its coverage (the images hold
// the rest), and a near tree, drawn with the finest cloud, still draws the full chain.
class CapturedWood : public WoodInImpostors, public testing::WithParamInterface<const char*> {};

TEST_P(CapturedWood, IsInTheImagesNotTheGeometry) {
  const std::string method = GetParam();
  // Multi-layer: a far cloud of 6 planes and 2 texels a hash cell, so that this 400-leaf tree's
  // billboards span the branches and their texels resolve them (its default, 100 planes of
  // 4 leaves at 1 texel a cell, is sized for trees of thousands of leaves). Classic cloud: one
  // bound for both coarse clouds, and the fixed alpha test, whose thresholded coverage the
  // bounds below were measured with (the hashed test dithers the thin captured branches'
  // partial coverage, which a per-pixel coverage error counts against any capture: 0.248
  // captured against 0.162 drawing the wood and 0.316 without).
  const nlohmann::json base =
      method == "multilayer_indirect"
          ? nlohmann::json{{"clusters", 60}, {"lowres_texels_per_cell", 2}}
          : nlohmann::json{{"wood_capture_far_px", 0.0}, {"alpha_test", "fixed"}};
  const auto with = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json params = base;
    params[key] = value;
    return params;
  };
  auto reference = test::bakeAndUpload(device, tree, "polygonal", nlohmann::json::object());
  auto plain = test::bakeAndUpload(device, tree, method, with("wood_capture_px", 0.0),
                                   Shading::kUnlit, "plain");
  auto captured = test::bakeAndUpload(device, tree, method, with("wood_capture_px", 8.0),
                                      Shading::kUnlit, "captured");
  const nlohmann::json report = captured->bakeReport();
  const auto capturedTriangles = report.at("wood_captured").at("triangles").get<size_t>();
  EXPECT_GT(capturedTriangles, tree.wood.triangleCount() / 4) << report.dump();
  EXPECT_EQ(plain->bakeReport().at("wood_captured").at("triangles").get<size_t>(), 0u);
  // 8 radii: about 22 px of radius, the far cloud.
  const auto [referenceDrawn, referenceImage] = drawAt(*reference, 8.0f);
  const auto [plainDrawn, plainImage] = drawAt(*plain, 8.0f);
  const auto [capturedDrawn, capturedImage] = drawAt(*captured, 8.0f);
  // Measured (classic cloud): 858 against 1652 primitives (residual wood level 2, 806
  // triangles, against the full chain's 1600).
  EXPECT_LT(capturedDrawn.counts.primitives * 3, plainDrawn.counts.primitives * 2);
  const size_t residualFrom = size_t(
      std::count_if(report.at("wood_levels").begin(), report.at("wood_levels").end(),
                    [](const nlohmann::json& level) { return !level.at("residual").get<bool>(); }));
  ASSERT_GT(capturedDrawn.woodInstancesPerLevel.size(), residualFrom);
  for (size_t level = 0; level < residualFrom; ++level)
    EXPECT_EQ(capturedDrawn.woodInstancesPerLevel[level], 0u) << "full chain at level " << level;
  // Coverage: the images hold the wood the geometry no longer draws. Measured on this small
  // tree's 26-plane far cloud: coverage error 0.197 drawing all wood, 0.235 with the wood
  // captured at 8 px (flattened onto the planes), 0.490 without any wood; the bounds sit between.
  // Not asserted for multi-layer: its low-resolution texels (one or two a hash cell) are too
  // coarse for this tree's thin branches, which they thicken (0.321 against 0.196 without wood,
  // 0.256 drawing it; docs/METHODS.md, "multi-layer speed"); the capture itself is checked by
  // LayeredBillboard.CapturedWoodAndLeavesHideOneAnotherByHeight.
  if (method == "billboard_cloud") {
    auto woodless =
        test::bakeAndUpload(device, tree, method, with("wood", false), Shading::kUnlit, "woodless");
    const double plainError = compareImages(referenceImage, plainImage).coverageError;
    const double capturedError = compareImages(referenceImage, capturedImage).coverageError;
    const double woodlessError =
        compareImages(referenceImage, drawAt(*woodless, 8.0f).second).coverageError;
    EXPECT_LT(capturedError, plainError + 0.06) << plainError;
    EXPECT_LT(capturedError, 0.5 * (plainError + woodlessError)) << woodlessError;
  }
  // 1.2 radii: the finest cloud, which holds no wood, with the full chain.
  const auto [nearDrawn, nearImage] = drawAt(*captured, 1.2f);
  EXPECT_EQ(nearDrawn.woodInstancesPerLevel.at(0), 1u);
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

INSTANTIATE_TEST_SUITE_P(ImageClouds, CapturedWood,
                         testing::Values("billboard_cloud", "multilayer_indirect"));

// wood_capture_far_px: the far cloud holds the wood within its own, larger bound, so a far tree
// draws less wood than with wood_capture_px alone, while a tree drawn with the middle cloud
// draws what it drew before; the far images hold the wood the geometry no longer draws. The
// multi-layer middle cloud is drawn as images below lod_lowres_px (90 px here), as the classic
// one always is.
class FarCloudWood : public WoodInImpostors, public testing::WithParamInterface<const char*> {};

TEST_P(FarCloudWood, CapturesTheWoodWithinItsOwnBound) {
  const std::string method = GetParam();
  auto reference = test::bakeAndUpload(device, tree, "polygonal", nlohmann::json::object());
  // The classic cloud: the fixed alpha test, as CapturedWood explains. Multi-layer: planes and
  // texels sized for this 400-leaf tree, as there.
  const nlohmann::json base =
      method == "multilayer_indirect"
          ? nlohmann::json{{"clusters", 60}, {"lowres_texels_per_cell", 2}, {"lod_lowres_px", 90.0}}
          : nlohmann::json{{"alpha_test", "fixed"}};
  const auto with = [&](const nlohmann::json& wood) {
    nlohmann::json params = base;
    params.update(wood);
    return params;
  };
  const auto capture = [&](double middlePixels, double farPixels) {
    return with({{"wood_capture_px", middlePixels}, {"wood_capture_far_px", farPixels}});
  };
  auto shared =
      test::bakeAndUpload(device, tree, method, capture(2.0, 0.0), Shading::kUnlit, "shared");
  auto ownFar =
      test::bakeAndUpload(device, tree, method, capture(2.0, 8.0), Shading::kUnlit, "own far");
  const nlohmann::json captured = ownFar->bakeReport().at("wood_captured");
  const auto sharedTriangles = captured.at("triangles").get<size_t>();
  EXPECT_EQ(sharedTriangles,
            shared->bakeReport().at("wood_captured").at("triangles").get<size_t>());
  const auto farTriangles = captured.at("far").at("triangles").get<size_t>();
  EXPECT_GT(farTriangles, sharedTriangles + tree.wood.triangleCount() / 4) << captured.dump();
  // Two residual chains after the full one: levels come in three equal runs.
  const nlohmann::json levels = ownFar->bakeReport().at("wood_levels");
  const size_t fullLevels = shared->bakeReport().at("wood_levels").size() / 2;
  ASSERT_EQ(levels.size(), 3 * fullLevels);
  // 8 radii: about 22 px of radius, the far cloud; the second residual chain.
  const auto [referenceDrawn, referenceImage] = drawAt(*reference, 8.0f);
  const auto [sharedDrawn, sharedImage] = drawAt(*shared, 8.0f);
  const auto [farDrawn, farImage] = drawAt(*ownFar, 8.0f);
  ASSERT_EQ(farDrawn.woodInstancesPerLevel.size(), levels.size());
  for (size_t level = 0; level < 2 * fullLevels; ++level)
    EXPECT_EQ(farDrawn.woodInstancesPerLevel[level], 0u) << level;
  EXPECT_LT(farDrawn.counts.primitives, sharedDrawn.counts.primitives);
  // Its images hold that wood: coverage nearer the drawn wood's than the woodless cloud's
  // (measured, classic cloud: 0.278 against 0.194 drawing the residual of 2 px, 0.490 without
  // wood; 102 primitives against 1,488). Not asserted for multi-layer, whose low-resolution
  // texels are too coarse for this tree's thin branches (CapturedWood).
  if (method == "billboard_cloud") {
    auto woodless = test::bakeAndUpload(device, tree, method, with({{"wood", false}}),
                                        Shading::kUnlit, "woodless");
    const double sharedError = compareImages(referenceImage, sharedImage).coverageError;
    const double farError = compareImages(referenceImage, farImage).coverageError;
    const double woodlessError =
        compareImages(referenceImage, drawAt(*woodless, 8.0f).second).coverageError;
    EXPECT_LT(farError, 0.5 * (sharedError + woodlessError)) << sharedError << " " << woodlessError;
  }
  // 3 radii: about 59 px, the middle cloud, with the first residual chain as before.
  const auto [sharedMiddle, sharedMiddleImage] = drawAt(*shared, 3.0f);
  const auto [farMiddle, farMiddleImage] = drawAt(*ownFar, 3.0f);
  EXPECT_EQ(farMiddle.counts.primitives, sharedMiddle.counts.primitives);
  ASSERT_EQ(farMiddle.woodInstancesPerLevel.size(), levels.size());
  uint64_t firstChain = 0;
  for (size_t level = fullLevels; level < 2 * fullLevels; ++level)
    firstChain += farMiddle.woodInstancesPerLevel[level];
  EXPECT_EQ(firstChain, 1u);
  // Both residual chains survive the saved asset: the far tree draws the same.
  test::TempDir dir;
  AssetFolder asset(dir.path());
  ownFar->save(asset);
  auto loaded = builtinMethods().find(method).create(ownFar->effectiveParams(), "loaded");
  AssetFolder reader(dir.path());
  loaded->load(reader);
  {
    gl::Device::OwnerScope scope(device, "loaded");
    loaded->upload(device);
  }
  EXPECT_EQ(drawAt(*loaded, 8.0f).second.pixels, farImage.pixels);
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

INSTANTIATE_TEST_SUITE_P(ImageClouds, FarCloudWood,
                         testing::Values("billboard_cloud", "multilayer_indirect"));

// The capture bounds as they take effect: a far bound below the near one is refused naming it;
// without coarse clouds, or without wood, nothing is captured and the written-back parameters
// say so.
TEST_P(FarCloudWood, BoundsAreCheckedAndWrittenBackAsTheyTakeEffect) {
  const auto& create = builtinMethods().find(GetParam()).create;
  for (const nlohmann::json& farBelowMiddle :
       {nlohmann::json{{"wood_capture_px", 8.0}, {"wood_capture_far_px", 4.0}},
        nlohmann::json{{"wood_capture_px", 20.0}, {"wood_capture_far_px", 16.0}}}) {
    try {
      create(farBelowMiddle, "test");
      ADD_FAILURE() << farBelowMiddle.dump() << " was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("wood_capture_far_px"), std::string::npos);
    }
  }
  for (const nlohmann::json& nothingToCapture :
       {nlohmann::json{{"lod", false}, {"wood_capture_px", 4.0}, {"wood_capture_far_px", 8.0}},
        nlohmann::json{{"wood", false}, {"wood_capture_px", 4.0}, {"wood_capture_far_px", 8.0}}}) {
    const auto method = create(nothingToCapture, "test");
    EXPECT_EQ(method->effectiveParams().at("wood_capture_px"), 0.0) << nothingToCapture.dump();
    EXPECT_EQ(method->effectiveParams().at("wood_capture_far_px"), 0.0) << nothingToCapture.dump();
  }
  const auto method = create({{"wood_capture_px", 2.0}, {"wood_capture_far_px", 8.0}}, "test");
  EXPECT_EQ(method->effectiveParams().at("wood_capture_far_px"), 8.0);
}

// lod_lowres_px: between it and lod_far_px the multi-layer middle cloud is drawn without its
// list walk, as its low-resolution texture (the same billboards, another image); above it, and
// for the far cloud below lod_far_px, nothing changes.
TEST_F(WoodInImpostors, MultilayerMiddleCloudDrawsItsLowResolutionTextureBelowLodLowresPx) {
  // Planes and texels sized for this 400-leaf tree, as in CapturedWood.
  const nlohmann::json base = {{"wood", false}, {"clusters", 60}, {"lowres_texels_per_cell", 2}};
  nlohmann::json lowRes = base;
  lowRes["lod_lowres_px"] = 90.0;
  auto reference = test::bakeAndUpload(device, tree, "polygonal", {{"wood", false}});
  auto walked =
      test::bakeAndUpload(device, tree, "multilayer_indirect", base, Shading::kUnlit, "walked");
  auto textured =
      test::bakeAndUpload(device, tree, "multilayer_indirect", lowRes, Shading::kUnlit, "textured");
  // 3 radii: about 59 px of radius, between lod_far_px (35) and lod_lowres_px.
  const auto [walkedDrawn, walkedImage] = drawAt(*walked, 3.0f);
  const auto [texturedDrawn, texturedImage] = drawAt(*textured, 3.0f);
  EXPECT_EQ(texturedDrawn.counts.primitives, walkedDrawn.counts.primitives) << "the same cloud";
  EXPECT_NE(texturedImage.pixels, walkedImage.pixels) << "another image";
  // The texture holds what the full walk shows, at two texels per hash cell: coverage within
  // 0.08 of the walk's (measured 0.372 against 0.315 on this sparse tree; an empty or misplaced
  // texture loses most of the crown).
  const ImageRgba8 referenceImage = drawAt(*reference, 3.0f).second;
  EXPECT_LT(compareImages(referenceImage, texturedImage).coverageError,
            compareImages(referenceImage, walkedImage).coverageError + 0.08);
  for (const float distance : {1.2f, 8.0f})  // the near cloud, the far cloud
    EXPECT_EQ(drawAt(*textured, distance).second.pixels, drawAt(*walked, distance).second.pixels)
        << distance << " radii";
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// Solid wood (WoodMesh::solid) is drawn with back faces culled, by the reference as by every
// impostor, and says so in the bake report: fewer fragments are shaded, and the image changes
// only where a tube's open end showed its inside.
TEST(WoodLevelsDrawn, SolidWoodCullsBackFacesInEveryMethod) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree solid = test::smallTree(400, 3);
  ASSERT_TRUE(solid.wood.solid);
  Tree doubleSided = solid;
  doubleSided.wood.solid = false;
  RenderSettings settings;
  settings.width = settings.height = 128;
  Harness harness(device, settings);
  harness.setTree(solid.bounds, solid.leaves.size());
  const Camera camera = orbitCamera(solid.bounds, {1.5f, 10.0f, 0.0f}, 40.0f);
  // At 1.5 radii of 128 px the classic cloud draws its middle cloud: without captured wood, so
  // that it draws the full chain, a closed mesh (a residual level is open, and culling it
  // changes the image: WoodRenderer::draw says why it is culled all the same).
  for (const std::string name : {"polygonal", "billboard_cloud"}) {
    const nlohmann::json params =
        name == "polygonal"
            ? nlohmann::json::object()
            : nlohmann::json{{"wood_capture_px", 0.0}, {"wood_capture_far_px", 0.0}};
    const auto render = [&](const Tree& tree, bool culled) {
      auto method = test::bakeAndUpload(device, tree, name, params, Shading::kUnlit,
                                        name + (culled ? " culled" : ""));
      EXPECT_EQ(method->bakeReport().at("wood_back_faces_culled").get<bool>(), culled) << name;
      DrawnStats drawn;
      const ImageRgbaF image = harness.renderLinearAt(*method, camera, 128, 128, &drawn);
      return std::make_pair(compositeToSrgb8(image, glm::vec3(0.5f)), drawn.counts.fragments);
    };
    const auto [culledImage, culledFragments] = render(solid, true);
    const auto [doubleSidedImage, doubleSidedFragments] = render(doubleSided, false);
    EXPECT_LT(culledFragments, doubleSidedFragments) << name;
    EXPECT_GT(compareImages(doubleSidedImage, culledImage).psnr, 35.0) << name;
  }
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

}  // namespace
}  // namespace canopy
