#include "methods/multilayer_indirect/layered_billboard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include <glm/geometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "common/metrics.h"
#include "common/random.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/leaf_images.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

struct LayeredFixture {
  Tree tree = test::smallTree(1500, 9);
  BillboardCloud cloud;
  LayeringParams params;
  std::vector<uint32_t> imageOfLeaf;
  explicit LayeredFixture(float maxSlope = 0.0f) {
    ClusteringParams clustering;
    clustering.clusters = 30;
    cloud = buildBillboardCloud(tree, clustering, 3);
    params.maxLayers = 255;
    params.maxSlope = maxSlope;
    imageOfLeaf.assign(tree.leaves.size(), 0u);
  }
};

TEST(LayeredBillboard, ListsAreFrontToBackAndHoldExactlyTheLeavesThatCanReachTheCell) {
  for (const float maxSlope : {0.0f, 1.5f}) {
    LayeredFixture f(maxSlope);
    for (const Billboard& billboard : f.cloud.billboards) {
      const LayeredBillboard layered =
          buildLayeredBillboard(f.tree, billboard, f.imageOfLeaf, f.params);
      EXPECT_EQ(layered.droppedEntries, 0u);
      ASSERT_EQ(layered.records.size(), billboard.leaves.size());
      for (int y = 0; y < layered.cells.y; ++y) {
        for (int x = 0; x < layered.cells.x; ++x) {
          const size_t cell = size_t(y) * layered.cells.x + x;
          // Independently: the leaves whose corners, seen along any ray up to the slope (a
          // corner at height z shows within z·slope of its projection), reach into this cell.
          const glm::vec2 lo = -layered.halfExtents + glm::vec2(x, y) * layered.cellSize;
          const glm::vec2 hi = lo + layered.cellSize;
          std::set<uint32_t> expected, listed;
          for (uint32_t leafIndex : billboard.leaves) {
            const Leaf& leaf = f.tree.leaves[leafIndex];
            glm::vec2 a(1e9f), b(-1e9f);
            for (int c = 0; c < 4; ++c) {
              const glm::vec3 corner = leaf.corner(c);
              const float z = std::abs(glm::dot(corner - billboard.center, billboard.normal));
              a = glm::min(a, billboard.toPlane(corner) - z * maxSlope);
              b = glm::max(b, billboard.toPlane(corner) + z * maxSlope);
            }
            const float e = 1e-5f;
            if (a.x < hi.x - e && b.x > lo.x + e && a.y < hi.y - e && b.y > lo.y + e)
              expected.insert(leafIndex);
          }
          for (uint32_t k = 0; k < layered.listLength[cell]; ++k) {
            const LeafRecord& record =
                layered.records[layered.entries[layered.listStart[cell] + k]];
            listed.insert(record.leaf);
            if (k > 0) {
              const LeafRecord& before =
                  layered.records[layered.entries[layered.listStart[cell] + k - 1]];
              EXPECT_GE(before.height, record.height) << "front to back";
            }
          }
          // Leaves that only touch a cell within rounding may or may not be listed.
          for (uint32_t leaf : expected) EXPECT_TRUE(listed.count(leaf)) << x << "," << y;
          EXPECT_LE(listed.size(), expected.size() + 2) << x << "," << y;
        }
      }
      // Parallax grows the rectangle by the corners' heights times the slope; without, it is the
      // billboard's own.
      if (maxSlope == 0.0f) {
        EXPECT_EQ(layered.halfExtents, billboard.halfExtents);
      }
      EXPECT_GE(layered.halfExtents.x, billboard.halfExtents.x);
    }
  }
}

TEST(LeafRecord, LocatesTheLeafPointEveryRayCrosses) {
  // Independently in 3D: a leaf point, a ray through it, the ray's crossing of the billboard
  // plane; locate() from that crossing must give back the leaf point's (s, t).
  const Tree tree = test::smallTree(200, 5);
  Billboard billboard;
  billboard.center = {0.2f, 1.0f, -0.3f};
  billboard.normal = glm::normalize(glm::vec3(0.3f, 0.2f, 1.0f));
  billboard.axisU = glm::normalize(glm::cross(glm::vec3(0, 1, 0), billboard.normal));
  billboard.axisV = glm::cross(billboard.normal, billboard.axisU);
  Random random(11, 3);
  int checked = 0;
  for (size_t i = 0; i < tree.leaves.size(); i += 7) {
    const Leaf& leaf = tree.leaves[i];
    const LeafRecord record = makeLeafRecord(leaf, billboard, 0);
    for (int trial = 0; trial < 4; ++trial) {
      const glm::vec2 st(random.uniform() * 2 - 1, random.uniform() * 2 - 1);
      const glm::vec3 point = leaf.center + leaf.axisU * (st.x * leaf.halfExtents.x) +
                              leaf.axisV * (st.y * leaf.halfExtents.y);
      glm::vec3 direction(random.uniform() - 0.5f, random.uniform() - 0.5f, 1.0f);
      direction = glm::normalize(direction.x * billboard.axisU + direction.y * billboard.axisV +
                                 direction.z * billboard.normal);
      const float dn = glm::dot(direction, billboard.normal);
      const glm::vec2 slope(glm::dot(direction, billboard.axisU) / dn,
                            glm::dot(direction, billboard.axisV) / dn);
      const float height = glm::dot(point - billboard.center, billboard.normal);
      const glm::vec3 crossing = point - direction * (height / dn);
      const auto found = record.locate(billboard.toPlane(crossing), slope);
      if (std::abs(glm::dot(glm::cross(leaf.axisU, leaf.axisV), direction)) < 0.05f) continue;
      ASSERT_TRUE(found);
      EXPECT_NEAR(found->x, st.x, 1e-3f);
      EXPECT_NEAR(found->y, st.y, 1e-3f);
      EXPECT_NEAR(record.heightAt(*found), height, 1e-4f);
      ++checked;
    }
  }
  EXPECT_GT(checked, 80);
}

// Two leaves stacked along the normal of a 0.4 × 0.4 billboard (same position and orientation,
// 0.2 apart), layered in 4 × 4 cells.
struct StackedLeaves {
  Tree tree = test::smallTree(50);
  Billboard billboard;
  LeafImages images;
  LayeredBillboard layered;
  StackedLeaves() {
    Leaf front = tree.leaves[0];
    front.center = {0, 0, 0.1f};
    front.normal = {0, 0, 1};
    front.axisU = {1, 0, 0};
    front.axisV = {0, 1, 0};
    front.halfExtents = {0.05f, 0.1f};
    Leaf back = front;
    back.center = {0, 0, -0.1f};
    tree.leaves = {front, back};
    billboard.normal = {0, 0, 1};
    billboard.axisU = {1, 0, 0};
    billboard.axisV = {0, 1, 0};
    billboard.halfExtents = {0.2f, 0.2f};
    billboard.leaves = {1, 0};
    LayeringParams params;
    params.cellSize = 0.1f;
    const LeafImageSampler sampler(tree);
    images = buildLeafImages(tree, sampler, 32, 16);
    layered = buildLayeredBillboard(tree, billboard, images.imageOfLeaf, params);
  }
};

TEST(LayeredBillboard, WalkFromEitherSideReturnsTheLeafNearestThatSide) {
  const StackedLeaves stacked;
  const LayeredBillboard& layered = stacked.layered;
  const LeafImages& images = stacked.images;
  const auto fromFront = walkLayers(layered, images.layers, {0.0f, 0.0f}, true);
  const auto fromBack = walkLayers(layered, images.layers, {0.0f, 0.0f}, false);
  ASSERT_TRUE(fromFront && fromBack);
  EXPECT_EQ(layered.records[fromFront->record].leaf, 0u);
  EXPECT_EQ(layered.records[fromBack->record].leaf, 1u);
  // Seen from the back, the leaf shows its underside image.
  EXPECT_NE(fromFront->color, fromBack->color);
  // Outside both leaves: nothing.
  EXPECT_FALSE(walkLayers(layered, images.layers, {0.18f, 0.18f}, true));
}

// Wood in the low-resolution texture (wood_capture_px): a red triangle spanning the rectangle
// shows wherever no leaf lies nearer the capturing side, and hides the leaves it lies in front of.
TEST(LayeredBillboard, CapturedWoodAndLeavesHideOneAnotherByHeight) {
  StackedLeaves stacked;  // 4 × 4 cells, 16 × 16 texels at 4 a cell
  Tree& tree = stacked.tree;
  const LayeredBillboard& layered = stacked.layered;
  const LeafImages& images = stacked.images;
  const Billboard& billboard = stacked.billboard;
  tree.woodMaterials = {WoodMaterial{"red", {1.0f, 0.0f, 0.0f, 1.0f}, -1}};
  const auto capture = [&](float woodHeight, bool fromFront) {
    tree.wood = {};
    tree.wood.positions = {{-1, -1, woodHeight}, {3, -1, woodHeight}, {-1, 3, woodHeight}};
    tree.wood.normals.assign(3, {0, 0, 1});
    tree.wood.uvs.assign(3, {0, 0});
    tree.wood.indices = {0, 1, 2};
    tree.wood.materialIds = {0};
    const WoodColorSampler colors(tree);
    const std::vector<uint32_t> triangles = {0};
    const LayeredWood wood{tree, colors, triangles, billboard};
    return captureLayered(layered, images.layers, 4, fromFront, nullptr, &wood);
  };
  for (const bool fromFront : {true, false}) {
    const ImageRgba8 leaves = captureLayered(layered, images.layers, 4, fromFront);
    const ImageRgba8 between = capture(0.0f, fromFront);
    const ImageRgba8 over = capture(fromFront ? 0.2f : -0.2f, fromFront);
    int leafTexels = 0, woodTexels = 0;
    for (int y = 0; y < leaves.height; ++y) {
      for (int x = 0; x < leaves.width; ++x) {
        const uint8_t* red = over.at(x, y);
        EXPECT_EQ(std::vector<int>(red, red + 4), (std::vector<int>{255, 0, 0, 255}))
            << "wood over the leaves hides them at " << x << ", " << y;
        const uint8_t* leaf = leaves.at(x, y);
        const uint8_t* mixed = between.at(x, y);
        EXPECT_EQ(mixed[3], 255) << "the wood fills the rest";
        if (leaf[3] == 255) {
          ++leafTexels;
          EXPECT_EQ(std::vector<int>(mixed, mixed + 3), std::vector<int>(leaf, leaf + 3))
              << "the nearer leaf shows at " << x << ", " << y;
        } else if (leaf[3] == 0) {
          ++woodTexels;
          EXPECT_EQ(std::vector<int>(mixed, mixed + 3), (std::vector<int>{255, 0, 0}));
        }
      }
    }
    EXPECT_GT(leafTexels, 4);
    EXPECT_GT(woodTexels, 100);
  }
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

// A tree of the given leaves only (no wood, no branch hierarchy).
Tree leavesOnly(std::vector<Leaf> leaves, const char* name) {
  Tree tree = test::smallTree(50);
  for (Leaf& leaf : leaves) leaf.branch = -1;
  tree.leaves = std::move(leaves);
  tree.branches.clear();
  tree.wood = {};
  tree.woodMaterials.clear();
  finalizeTree(tree, name);
  return tree;
}

TEST(MultilayerIndirect, ABillboardWithOneLeafDrawsItsTrueOutlineWhereThePolygonalLeafIs) {
  // Rotated 45° in its plane, and tilted 50° away from the camera: the record's frame maps the
  // plane into the leaf, so outline, size and place match the polygon's (no orientation bins).
  for (const float tilt : {0.0f, 50.0f}) {
    Leaf leaf = test::smallTree(50).leaves[0];
    leaf.center = {0.3f, 1.0f, -0.2f};
    const float a = tilt * 3.14159265f / 180.0f;
    leaf.normal = {std::sin(a), 0.0f, std::cos(a)};
    leaf.axisV = glm::normalize(glm::vec3(0, 1, 0) + glm::vec3(std::cos(a), 0, -std::sin(a)));
    leaf.axisU = glm::normalize(glm::cross(leaf.axisV, leaf.normal));
    leaf.normal = glm::cross(leaf.axisU, leaf.axisV);
    const Tree tree = leavesOnly({leaf}, "one leaf");
    // The camera looks along +z: a single leaf's billboard is its own plane.
    const auto renders =
        renderBoth(tree, {{"clusters", 1}, {"lod", false}, {"wood", false}, {"hash_resolution", 8}},
                   {0, 0, 1}, {0, 1, 0});
    long referenceCount = 0, methodCount = 0;
    const glm::vec2 p = coverageCentroid(renders.reference, &referenceCount);
    const glm::vec2 q = coverageCentroid(renders.method, &methodCount);
    ASSERT_GT(referenceCount, 200);
    // Same place within half a pixel, same area within 5 % (leaf image resampling).
    EXPECT_LT(glm::length(p - q), 0.5f) << "tilt " << tilt;
    EXPECT_NEAR(double(methodCount) / double(referenceCount), 1.0, 0.05) << "tilt " << tilt;
  }
}

TEST(MultilayerIndirect, ParallaxDrawsLeavesOffThePlaneWhereTheyAre) {
  // Two parallel leaves 0.6 apart along the billboard normal; seen 40° off the normal, the
  // paper's lookup draws them where the plane flattened them, parallax where they are.
  Leaf leaf = test::smallTree(50).leaves[0];
  leaf.normal = {0, 0, 1};
  leaf.axisU = {1, 0, 0};
  leaf.axisV = {0, 1, 0};
  leaf.halfExtents = {0.15f, 0.25f};
  Leaf near = leaf, far = leaf;
  near.center = {-0.4f, 1.0f, 0.3f};
  far.center = {0.4f, 1.0f, -0.3f};
  const Tree tree = leavesOnly({near, far}, "two leaves");
  const glm::vec3 view = glm::normalize(glm::vec3(std::sin(0.7f), 0.0f, std::cos(0.7f)));
  const nlohmann::json base = {{"clusters", 1},
                               {"lod", false},
                               {"wood", false},
                               {"lod_factor", 0.0},
                               {"hash_resolution", 16}};
  nlohmann::json withParallax = base;
  withParallax["parallax"] = true;
  const auto flat = renderBoth(tree, base, view, {0, 1, 0}, 6.0f);
  const auto parallax = renderBoth(tree, withParallax, view, {0, 1, 0}, 6.0f);
  const ImageMetrics flatMetrics = compareImages(flat.reference, flat.method);
  const ImageMetrics parallaxMetrics = compareImages(parallax.reference, parallax.method);
  EXPECT_GT(flatMetrics.coverageError, 0.1) << "flattened leaves are displaced";
  EXPECT_LT(parallaxMetrics.coverageError, 0.05);
  EXPECT_GT(flatMetrics.coverageError, 3.0 * parallaxMetrics.coverageError);
  EXPECT_GT(parallaxMetrics.psnr, 30.0);
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
  // Two leaves side by side leaning ±51° about their vertical axes: one billboard facing +z holds
  // both. A light along the left leaf's normal makes it bright and the right one dark in the
  // reference; the impostor must agree, which the billboard's normal alone cannot (it would
  // shade both alike). The record's frame gives each leaf its exact normal.
  const float facing = 0.625f, lean = std::sqrt(1.0f - facing * facing);
  std::vector<Leaf> leaves;
  for (const float side : {-1.0f, 1.0f}) {
    Leaf leaf = test::smallTree(50).leaves[0];
    leaf.center = {side * 0.6f, 1.0f, 0.0f};
    leaf.axisV = {0, 1, 0};
    leaf.normal = glm::normalize(glm::vec3(side * lean, 0.0f, facing));
    leaf.axisU = glm::normalize(glm::cross(leaf.axisV, leaf.normal));
    leaf.halfExtents = {0.2f, 0.3f};
    leaves.push_back(leaf);
  }
  const Tree tree = leavesOnly(leaves, "two leaning leaves");
  const glm::vec3 light = leaves[0].normal;
  const auto renders = renderBoth(tree,
                                  {{"clusters", 1},
                                   {"lod", false},
                                   {"wood", false},
                                   {"ambient_occlusion", false},
                                   {"hash_resolution", 16}},
                                  {0, 0, 1}, {0, 1, 0}, 6.0f, &light);
  const glm::vec3 refLeft = meanColour(renders.reference, true),
                  refRight = meanColour(renders.reference, false);
  const glm::vec3 left = meanColour(renders.method, true),
                  right = meanColour(renders.method, false);
  ASSERT_GT(refLeft.g, 1.5f * refRight.g) << "the reference shades them apart";
  // Same shading within 4 % (interpolated vertex normals against one per record).
  EXPECT_NEAR(left.g, refLeft.g, 0.04f * refLeft.g);
  EXPECT_NEAR(right.g, refRight.g, 0.04f * refLeft.g);
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

TEST(MultilayerIndirect, FarLevelKeepsASparseCrownsCoverage) {
  // The far level is the low-resolution texture alone, one texel a hash cell: on a sparse crown
  // most texels are partly covered, and an alpha test at 0.5 dropped them (the crown thinned to
  // its branches). The hashed threshold keeps each texel's coverage in expectation, so the
  // crown's total alpha (2× supersampled, partial pixels count partly) stays near the reference's.
  const Tree tree = test::smallTree(1000, 3);  // the sparse preset's own leaf count
  VariantBench bench(128);
  const Camera camera = orbitCamera(tree.bounds, {6.0f, 20.0f, 40.0f}, 40.0f);
  auto impostor = bench.bake(
      tree, {{"lod_near_px", 100000.0}, {"lod_far_px", 99999.0}, {"wood", false}}, "far");
  auto reference = test::bakeAndUpload(bench.device, tree, "polygonal", {{"wood", false}},
                                       Shading::kUnlit, "reference");
  const auto totalAlpha = [](const ImageRgba8& image) {
    double sum = 0.0;
    for (size_t i = 3; i < image.pixels.size(); i += 4) sum += image.pixels[i] / 255.0;
    return sum;
  };
  const double referenceAlpha = totalAlpha(bench.harness.render(*reference, camera));
  ASSERT_GT(referenceAlpha, 100.0) << "the reference shows the crown";
  const double ratio = totalAlpha(bench.harness.render(*impostor, camera)) / referenceAlpha;
  // Measured: 0.82 of the reference's alpha hashed, 0.07 tested at 0.5.
  EXPECT_GT(ratio, 0.6);
  EXPECT_LT(ratio, 1.25);
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

// A shortened walk that missed takes the rest of the list from the low-resolution texel, whose
// coverage a counts every leaf of the cell, the walked ones too. lowres_fallback "rest" counts
// only the leaves not walked, 1 - (1 - a)^share <= a: it keeps a subset of what "all" keeps, and
// less wherever walks are shortened.
TEST(MultilayerIndirect, LowResolutionFallbackRestKeepsASubsetOfAll) {
  const Tree tree = test::smallTree(800, 4);
  const auto render = [&](const char* fallback) {
    const nlohmann::json params = {{"clusters", 20},
                                   {"lod", false},
                                   {"wood", false},
                                   {"lod_factor", 0.05},
                                   {"lowres_fallback", fallback}};
    return renderBoth(tree, params, {0, 0, 1}, {0, 1, 0}).method;
  };
  const ImageRgba8 rest = render("rest"), all = render("all");
  long restCovered = 0, allCovered = 0, outside = 0;
  for (size_t i = 3; i < rest.pixels.size(); i += 4) {
    restCovered += rest.pixels[i];
    allCovered += all.pixels[i];
    outside += rest.pixels[i] > all.pixels[i];
  }
  EXPECT_EQ(outside, 0) << "pixels more covered with rest than with all";
  EXPECT_LT(restCovered, allCovered);
}

TEST(MultilayerIndirect, EightBitRecordsDrawLikeFloatRecordsInHalfTheMemoryAndSurviveSaveLoad) {
  const Tree tree = test::smallTree(800, 4);
  VariantBench bench(160);
  gl::Ledger& ledger = bench.ledger;
  gl::Device& device = bench.device;
  Harness& harness = bench.harness;
  const Camera camera = orbitCamera(tree.bounds, {2.0f, 20.0f, 40.0f}, 40.0f);
  std::map<std::string, std::unique_ptr<Method>> methods;
  for (const std::string precision : {"float16", "8bit"}) {
    methods[precision] = bench.bake(
        tree,
        {{"clusters", 20}, {"lod", false}, {"lists_precision", precision}, {"compression", "none"}},
        precision);
  }
  const ImageRgba8 exact = harness.render(*methods["float16"], camera);
  const ImageRgba8 packed = harness.render(*methods["8bit"], camera);
  // 16-bit positions and 8-bit frames move a leaf edge by well under a pixel here: a few pixels
  // change, the image stays the same picture.
  const ImageMetrics metrics = compareImages(exact, packed);
  EXPECT_GT(metrics.psnr, 30.0);
  EXPECT_LT(metrics.coverageError, 0.01);
  EXPECT_NE(exact, packed) << "the records really are quantized";
  // Records RGBA16F + RGBA16F + RG16F + AO RGBA8 (24 bytes) → RGBA16UI + RGBA8 + AO RGBA4
  // (14 bytes): 10 bytes per record slot (rows of 1024 records) saved; lists, hash and images
  // unchanged.
  const double saved = double(ledger.totals("float16").texture) - ledger.totals("8bit").texture;
  const auto records = methods["8bit"]->bakeReport().at("records").get<double>();
  EXPECT_EQ(saved, 10.0 * 1024.0 * std::ceil(records / 1024.0));
  // Save and load: the 8-bit blobs are what is stored, and draw the same image.
  test::TempDir dir;
  AssetFolder asset(dir.path());
  methods["8bit"]->save(asset);
  EXPECT_FALSE(std::filesystem::exists(dir / "records_c.bin")) << "float16's third plane";
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

TEST(MultilayerIndirect, BillboardsCostOneRecordEachAndCorruptRecordsNameTheAsset) {
  const Tree tree = test::smallTree(400, 5);
  VariantBench bench(96);
  const auto method = bench.bake(tree, {{"clusters", 30}, {"lod", false}, {"wood", false}}, "ml");
  // No vertex or index buffer: the geometry is the billboards' 48-byte records.
  const auto billboards = method->bakeReport().at("clouds")[0].at("billboards").get<uint64_t>();
  EXPECT_EQ(bench.ledger.totals("ml").geometry, billboards * 48);

  test::TempDir dir;
  {
    AssetFolder asset(dir.path());
    method->save(asset);
  }
  const std::filesystem::path blob = dir / "billboards.bin";
  std::string bytes = test::readText(blob);
  ASSERT_EQ(bytes.size(), billboards * 48);
  const auto expectLoadError = [&](const std::string& contents, const std::string& what) {
    test::writeText(blob, contents);
    auto loaded =
        builtinMethods().find("multilayer_indirect").create(method->effectiveParams(), "t");
    test::expectLoadErrorNamesTheFolder(*loaded, dir.path(), what);
  };
  expectLoadError(bytes.substr(0, bytes.size() - 5), "truncated");
  std::string outside = bytes;
  outside[36] = outside[37] = outside[38] = outside[39] = '\xff';  // hash cells of the first
  expectLoadError(outside, "hash cells outside the atlas");
  std::string missing = bytes;
  missing[28] = missing[29] = missing[30] = missing[31] = '\x7f';  // its first leaf record
  expectLoadError(missing, "a missing leaf record");
}

// view_orders (the contract test checks the images): 16-bit orders of the walked clouds' (near
// and middle) billboards, two to a word, per direction.
TEST(MultilayerIndirect, ViewOrdersCostTwoBytesPerWalkedBillboardAndDirection) {
  const Tree tree = test::smallTree(800, 4);
  VariantBench bench(64);
  std::map<int, std::unique_ptr<Method>> methods;
  for (const int orders : {0, 8}) {
    methods[orders] = bench.bake(tree, {{"clusters", 40}, {"view_orders", orders}},
                                 "orders" + std::to_string(orders));
  }
  const auto clouds = methods[8]->bakeReport().at("clouds");
  const uint64_t walked =
      clouds[0].at("billboards").get<uint64_t>() + clouds[1].at("billboards").get<uint64_t>();
  EXPECT_EQ(bench.ledger.totals("orders8").geometry - bench.ledger.totals("orders0").geometry,
            4 * ((8 * walked + 1) / 2));
}

TEST(MultilayerIndirect, BadParametersNameTheParameter) {
  test::expectParameterErrorsNameTheKey("multilayer_indirect", {{"hash_resolution", 0},
                                                                {"max_layers", 256},
                                                                {"parallax_max_angle", 90.0},
                                                                {"lod_factor", -1.0},
                                                                {"parallax", "yes"},
                                                                {"lod_lowres_px", 20.0},
                                                                {"lod_lowres_px", 200.0},
                                                                {"view_orders", 65}});
}

}  // namespace
}  // namespace canopy
