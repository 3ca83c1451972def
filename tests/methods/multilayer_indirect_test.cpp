#include "methods/multilayer_indirect/layered_billboard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include <glm/geometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "common/metrics.h"
#include "methods/common/leaf_capture.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

struct LayeredFixture {
  Tree tree = test::smallTree(1500, 9);
  BillboardCloud cloud;
  LayeringParams params;
  LayeredFixture(SpriteRule rule = SpriteRule::kPaper) {
    ClusteringParams clustering;
    clustering.clusters = 30;
    cloud = buildBillboardCloud(tree, clustering, 3);
    params.sprite = rule;
    params.maxLayers = 255;
  }
};

TEST(LayeredBillboard, ListsAreFrontToBackAndHoldExactlyTheOverlappingSprites) {
  for (SpriteRule rule : {SpriteRule::kPaper, SpriteRule::kBounds}) {
    LayeredFixture f(rule);
    for (const Billboard& billboard : f.cloud.billboards) {
      const LayeredBillboard layered = buildLayeredBillboard(f.tree, billboard, f.params);
      EXPECT_EQ(layered.droppedEntries, 0u);
      for (int y = 0; y < layered.cells.y; ++y) {
        for (int x = 0; x < layered.cells.x; ++x) {
          const size_t cell = size_t(y) * layered.cells.x + x;
          // Independently: the leaves whose sprite square overlaps this cell with positive area.
          const glm::vec2 lo = -billboard.halfExtents + glm::vec2(x, y) * layered.cellSize;
          const glm::vec2 hi = lo + layered.cellSize;
          std::set<uint32_t> expected, listed;
          for (uint32_t leaf : billboard.leaves) {
            const LayerEntry sprite = leafSprite(f.tree.leaves[leaf], billboard, rule);
            const glm::vec2 a = sprite.position - 0.5f * sprite.size,
                            b = sprite.position + 0.5f * sprite.size;
            const bool inside = a.x < hi.x && b.x > lo.x && a.y < hi.y && b.y > lo.y;
            // Sprites touching the border cells from outside the billboard are clamped into them.
            if (inside) expected.insert(leaf);
          }
          for (uint32_t k = 0; k < layered.listLength[cell]; ++k) {
            const LayerEntry& entry = layered.entries[layered.listStart[cell] + k];
            listed.insert(entry.leaf);
            if (k > 0) {
              EXPECT_GE(layered.entries[layered.listStart[cell] + k - 1].depth, entry.depth)
                  << "front to back";
            }
          }
          EXPECT_EQ(listed, expected) << "cell " << x << "," << y;
        }
      }
    }
  }
}

TEST(LayeredBillboard, WalkFromEitherSideReturnsTheLeafNearestThatSide) {
  // Two leaves stacked along the billboard normal, same position and orientation.
  Tree tree = test::smallTree(50);
  Leaf front = tree.leaves[0];
  front.center = {0, 0, 0.1f};
  front.normal = {0, 0, 1};
  front.axisU = {1, 0, 0};
  front.axisV = {0, 1, 0};
  front.halfExtents = {0.05f, 0.1f};
  Leaf back = front;
  back.center = {0, 0, -0.1f};
  tree.leaves = {front, back};
  Billboard billboard;
  billboard.normal = {0, 0, 1};
  billboard.axisU = {1, 0, 0};
  billboard.axisV = {0, 1, 0};
  billboard.halfExtents = {0.2f, 0.2f};
  billboard.leaves = {1, 0};
  LayeringParams params;
  params.hashResolution = 4;
  const LayeredBillboard layered = buildLayeredBillboard(tree, billboard, params);
  const LeafImageSampler sampler(tree);
  const auto images = buildOrientedLeafImages(tree, sampler, params.bins, 32);
  const auto fromFront = walkLayers(layered, billboard, images, params.bins, {0.0f, 0.0f}, true);
  const auto fromBack = walkLayers(layered, billboard, images, params.bins, {0.0f, 0.0f}, false);
  ASSERT_TRUE(fromFront && fromBack);
  EXPECT_EQ(layered.entries[fromFront->entry].leaf, 0u);
  EXPECT_EQ(layered.entries[fromBack->entry].leaf, 1u);
  // Seen from the back, the leaf shows its underside image.
  EXPECT_NE(fromFront->color, fromBack->color);
  // Outside both leaves: nothing.
  EXPECT_FALSE(walkLayers(layered, billboard, images, params.bins, {0.18f, 0.18f}, true));
}

// Renders `method` and the reference for a tree, camera along the billboard normal.
struct TwoRenders {
  ImageRgba8 reference, method;
};
TwoRenders renderBoth(const Tree& tree, const nlohmann::json& params, glm::vec3 normal,
                      glm::vec3 up, float fov = 3.0f, const glm::vec3* light = nullptr) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  RenderSettings settings;
  settings.width = settings.height = 128;
  settings.fovYDegrees = fov;
  if (light) {
    settings.shading = Shading::kLit;
    settings.lightDirection = *light;
    settings.ambient = 0.2f;
  }
  Harness harness(device, settings);
  const float radius = tree.boundingSphereRadius();
  Camera camera;
  camera.target = tree.bounds.center();
  camera.position = camera.target + normal * (radius * 40.0f);
  camera.up = up;
  camera.fovYDegrees = fov;
  camera.nearPlane = radius * 30.0f;
  camera.farPlane = radius * 50.0f;
  TwoRenders out;
  for (const std::string name : {"polygonal", "multilayer_indirect"}) {
    auto m = builtinMethods().find(name).create(
        name == "polygonal" ? nlohmann::json{{"wood", false}} : params, "test");
    BakeContext ctx;
    m->bake(tree, ctx);
    gl::Device::OwnerScope scope(device, name);
    m->upload(device);
    (name == "polygonal" ? out.reference : out.method) = harness.render(*m, camera);
  }
  return out;
}

glm::vec2 coverageCentroid(const ImageRgba8& image, long* count) {
  glm::dvec2 sum(0.0);
  long n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (image.at(x, y)[3] >= 128) sum += glm::dvec2(x, y), ++n;
    }
  }
  *count = n;
  return n ? glm::vec2(sum / double(n)) : glm::vec2(-1);
}

TEST(MultilayerIndirect, ABillboardWithOneLeafDrawsItWhereThePolygonalLeafIs) {
  Tree tree = test::smallTree(50);
  Leaf leaf = tree.leaves[0];
  leaf.center = {0.3f, 1.0f, -0.2f};
  leaf.normal = {0, 0, 1};
  leaf.axisV = glm::normalize(glm::vec3(1, 1, 0));  // rotated 45° in its plane
  leaf.axisU = glm::normalize(glm::cross(leaf.axisV, leaf.normal));
  leaf.normal = glm::cross(leaf.axisU, leaf.axisV);
  leaf.branch = -1;
  tree.leaves = {leaf};
  tree.branches.clear();
  tree.wood = {};
  tree.woodMaterials.clear();
  finalizeTree(tree, "one leaf");
  const auto renders = renderBoth(tree,
                                  {{"clusters", 1},
                                   {"lod", false},
                                   {"wood", false},
                                   {"sprite", "bounds"},
                                   {"rotations", 8},
                                   {"hash_resolution", 8}},
                                  leaf.normal, {0, 1, 0});
  long referenceCount = 0, methodCount = 0;
  const glm::vec2 a = coverageCentroid(renders.reference, &referenceCount);
  const glm::vec2 b = coverageCentroid(renders.method, &methodCount);
  ASSERT_GT(referenceCount, 200);
  // Same place within a pixel, same size within 15 % (quantized tilt and leaf image resampling).
  EXPECT_LT(glm::length(a - b), 1.0f) << a.x << "," << a.y << " vs " << b.x << "," << b.y;
  EXPECT_NEAR(double(methodCount) / double(referenceCount), 1.0, 0.15);
}

// Mean colour of the covered pixels in the left or right half.
glm::vec3 meanColour(const ImageRgba8& image, bool left) {
  glm::dvec3 sum(0.0);
  long n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = left ? 0 : image.width / 2; x < (left ? image.width / 2 : image.width); ++x) {
      const uint8_t* p = image.at(x, y);
      if (p[3] < 255) continue;
      sum += glm::dvec3(p[0], p[1], p[2]);
      ++n;
    }
  }
  return n ? glm::vec3(sum / double(n)) : glm::vec3(-1.0f);
}

TEST(MultilayerIndirect, LitLeavesAreShadedWithTheirOwnNormalsNotTheBillboards) {
  // Two leaves side by side leaning ±51° (|n·z| = 0.625, the centre of tilt bin 2 of 4) about
  // their vertical axes: one billboard facing +z holds both. A light along the left leaf's
  // normal makes it bright and the right one dark in the reference; the impostor must agree,
  // which the billboard's normal alone cannot (it would shade both alike).
  Tree tree = test::smallTree(50);
  const float facing = 0.625f, lean = std::sqrt(1.0f - facing * facing);
  std::vector<Leaf> leaves;
  for (const float side : {-1.0f, 1.0f}) {
    Leaf leaf = tree.leaves[0];
    leaf.center = {side * 0.6f, 1.0f, 0.0f};
    leaf.axisV = {0, 1, 0};
    leaf.normal = glm::normalize(glm::vec3(side * lean, 0.0f, facing));
    leaf.axisU = glm::normalize(glm::cross(leaf.axisV, leaf.normal));
    leaf.halfExtents = {0.2f, 0.3f};
    leaf.branch = -1;
    leaves.push_back(leaf);
  }
  tree.leaves = leaves;
  tree.branches.clear();
  tree.wood = {};
  tree.woodMaterials.clear();
  finalizeTree(tree, "two leaning leaves");
  const glm::vec3 light = leaves[0].normal;
  const auto renders = renderBoth(tree,
                                  {{"clusters", 1},
                                   {"lod", false},
                                   {"wood", false},
                                   {"ambient_occlusion", false},
                                   {"rotations", 64},
                                   {"tilts", 4},
                                   {"hash_resolution", 16}},
                                  {0, 0, 1}, {0, 1, 0}, 6.0f, &light);
  const glm::vec3 refLeft = meanColour(renders.reference, true),
                  refRight = meanColour(renders.reference, false);
  const glm::vec3 left = meanColour(renders.method, true),
                  right = meanColour(renders.method, false);
  ASSERT_GT(refLeft.g, 1.5f * refRight.g) << "the reference shades them apart";
  // Same shading within 10 % (the bin's mean foreshortening and 64 in-plane angles).
  EXPECT_NEAR(left.g, refLeft.g, 0.1f * refLeft.g);
  EXPECT_NEAR(right.g, refRight.g, 0.1f * refLeft.g);
}

// A headless context, ledger and harness, and multilayer_indirect variants baked into it.
struct VariantBench {
  std::unique_ptr<gl::Context> context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device{ledger};
  Harness harness;
  explicit VariantBench(int size) : harness(device, sizedSettings(size)) {}
  static RenderSettings sizedSettings(int size) {
    RenderSettings settings;
    settings.width = settings.height = size;
    return settings;
  }
  std::unique_ptr<Method> bake(const Tree& tree, const nlohmann::json& params,
                               const std::string& owner) {
    return test::bakeAndUpload(device, tree, "multilayer_indirect", params, Shading::kUnlit, owner);
  }
};

TEST(MultilayerIndirect, LowResolutionAmbientOcclusionDarkensOnlyLitFarTrees) {
  // lod thresholds just past the bounding sphere: from 2.5 radii the far level draws, which is
  // the low-resolution texture alone (§5.1, §6).
  LSystemTreeParams shrub = treePreset("shrub");  // dense foliage: the far level covers a lot
  shrub.leafTextureSize = 64;
  const Tree tree = generateTree(shrub, 4);
  VariantBench bench(128);
  Harness& harness = bench.harness;
  const Camera camera = orbitCamera(tree.bounds, {2.5f, 20.0f, 40.0f}, 40.0f);
  std::map<bool, std::unique_ptr<Method>> methods;
  for (const bool occlusion : {false, true}) {
    methods[occlusion] = bench.bake(tree,
                                    {{"clusters", 100},
                                     {"lod_near_px", 100000.0},  // the far level at any size
                                     {"lod_far_px", 99999.0},
                                     {"wood", false},
                                     {"ambient_occlusion", occlusion}},
                                    occlusion ? "ao" : "plain");
  }
  // Unlit: the AO lives in its own texture, so the images are the same.
  const ImageRgba8 plainUnlit = harness.render(*methods[false], camera);
  EXPECT_EQ(harness.render(*methods[true], camera), plainUnlit);
  long covered = 0;
  for (size_t i = 3; i < plainUnlit.pixels.size(); i += 4) covered += plainUnlit.pixels[i] > 0;
  ASSERT_GT(covered, 1000) << "the far level shows the tree";
  // Lit: the AO scales the ambient term of the far level.
  harness.settings().shading = Shading::kLit;
  const double plain = meanColour(harness.render(*methods[false], camera), true).g +
                       meanColour(harness.render(*methods[false], camera), false).g;
  const double occluded = meanColour(harness.render(*methods[true], camera), true).g +
                          meanColour(harness.render(*methods[true], camera), false).g;
  EXPECT_LT(occluded, plain - 1.0) << "occluded leaves lose ambient light";
}

TEST(MultilayerIndirect, ShaderLodWithAllEntriesEqualsFullEvaluation) {
  const Tree tree = test::smallTree(800, 4);
  const nlohmann::json base = {{"clusters", 20}, {"lod", false}, {"wood", false}};
  nlohmann::json all = base, generous = base;
  all["lod_factor"] = 0.0;          // evaluate every entry
  generous["lod_factor"] = 1000.0;  // a budget no list reaches
  const auto full = renderBoth(tree, all, {0, 0, 1}, {0, 1, 0}, 20.0f);
  const auto lod = renderBoth(tree, generous, {0, 0, 1}, {0, 1, 0}, 20.0f);
  EXPECT_EQ(full.method, lod.method);
  // A small factor evaluates fewer entries and so changes the image (the low-resolution fallback).
  nlohmann::json stingy = base;
  stingy["lod_factor"] = 0.01;
  EXPECT_NE(renderBoth(tree, stingy, {0, 0, 1}, {0, 1, 0}, 20.0f).method, full.method);
}

TEST(MultilayerIndirect, EightBitListsDrawLikeFloatListsInHalfTheMemoryAndSurviveSaveLoad) {
  const Tree tree = test::smallTree(800, 4);
  VariantBench bench(160);
  gl::Ledger& ledger = bench.ledger;
  gl::Device& device = bench.device;
  Harness& harness = bench.harness;
  const Camera camera = orbitCamera(tree.bounds, {2.0f, 20.0f, 40.0f}, 40.0f);
  std::map<std::string, std::unique_ptr<Method>> methods;
  for (const std::string precision : {"float16", "8bit"}) {
    methods[precision] = bench.bake(
        tree, {{"clusters", 20}, {"lod", false}, {"lists_precision", precision}}, precision);
  }
  const ImageRgba8 exact = harness.render(*methods["float16"], camera);
  const ImageRgba8 packed = harness.render(*methods["8bit"], camera);
  // Quantization moves sprites by at most (1 + 2·range)/510 cell: a few pixels change, the image
  // stays the same picture.
  const ImageMetrics metrics = compareImages(exact, packed);
  EXPECT_GT(metrics.psnr, 30.0);
  EXPECT_LT(metrics.coverageError, 0.01);
  EXPECT_NE(exact, packed) << "the lists really are quantized";
  // Lists RGBA16F → RGBA8 and AO RGBA8 → RGBA4: 6 of 12 bytes per entry saved.
  const double saved = double(ledger.totals("float16").texture) - ledger.totals("8bit").texture;
  const auto& report = methods["8bit"]->bakeReport();
  const double entries = report.at("list_entries").get<double>();
  EXPECT_NEAR(saved, 6.0 * entries, 1.0);
  // Save and load: the 8-bit blobs are what is stored, and draw the same image.
  test::TempDir dir;
  AssetFolder asset(dir.path());
  methods["8bit"]->save(asset);
  EXPECT_FALSE(std::filesystem::exists(dir / "lists.bin"));
  auto loaded = builtinMethods()
                    .find("multilayer_indirect")
                    .create(methods["8bit"]->effectiveParams(), "test");
  AssetFolder reader(dir.path());
  loaded->load(reader);
  {
    gl::Device::OwnerScope scope(device, "loaded");
    loaded->upload(device);
  }
  EXPECT_EQ(harness.render(*loaded, camera), packed);
}

TEST(MultilayerIndirect, BadParametersNameTheParameter) {
  test::expectParameterErrorsNameTheKey("multilayer_indirect", {{"hash_resolution", 0},
                                                                {"max_layers", 256},
                                                                {"sprite", "huge"},
                                                                {"lod_factor", -1.0},
                                                                {"rotations", 0}});
}

}  // namespace
}  // namespace canopy
