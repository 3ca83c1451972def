#include "methods/bbox_hierarchy/box_hierarchy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "common/lsystem.h"
#include "common/metrics.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

std::vector<BoxHierarchy> hierarchiesOf(const Tree& tree) {
  return {hierarchyFromBranches(tree), spatialHierarchy(tree, 50)};
}

TEST(BoxHierarchy, EveryLeafLiesInExactlyOneBoxPerLevel) {
  const Tree tree = test::smallTree(1200, 3);
  for (const BoxHierarchy& h : hierarchiesOf(tree)) {
    int maxLevel = 0;
    for (const BoxNode& n : h.nodes) maxLevel = std::max(maxLevel, n.level);
    std::vector<int> depthOfLeaf(tree.leaves.size(), -1);  // level of the node that owns each leaf
    for (const BoxNode& n : h.nodes) {
      for (uint32_t i = n.leafBegin; i < n.leafEnd; ++i) depthOfLeaf[h.leafOrder[i]] = n.level;
    }
    for (int level = 0; level <= maxLevel; ++level) {
      std::vector<int> count(tree.leaves.size(), 0);
      for (const BoxNode& n : h.nodes) {
        if (n.level != level) continue;
        for (uint32_t i = n.leafBegin; i < n.subtreeLeafEnd; ++i) {
          ++count[h.leafOrder[i]];
          for (int c = 0; c < 4; ++c) {
            EXPECT_TRUE(n.box.contains(tree.leaves[h.leafOrder[i]].corner(c), 1e-4f)) << h.source;
          }
        }
      }
      // A leaf owned at this level or deeper is in exactly one box of the level; others in none.
      for (size_t l = 0; l < tree.leaves.size(); ++l) {
        ASSERT_GE(depthOfLeaf[l], 0);
        EXPECT_EQ(count[l], depthOfLeaf[l] >= level ? 1 : 0)
            << h.source << " level " << level << " leaf " << l;
      }
    }
  }
}

// A wood mesh of three separate parts: a trunk and two branches starting on it at different
// heights, the upper branch attached to the lower one's tip; a leaf beside each part.
TEST(BoxHierarchy, WoodPartsBecomeBranchesHangingOnTheNearestLowerPart) {
  Tree tree = test::smallTree(50);
  tree.wood = {};
  tree.branches.clear();
  const auto addSegment = [&](glm::vec3 a, glm::vec3 b) {  // a thin triangle strip from a to b
    const auto base = static_cast<uint32_t>(tree.wood.positions.size());
    const glm::vec3 side(0.02f, 0, 0.02f);
    for (const glm::vec3& p : {a - side, a + side, b - side, b + side}) {
      tree.wood.positions.push_back(p);
      tree.wood.normals.push_back({0, 0, 1});
      tree.wood.uvs.push_back({0, 0});
    }
    tree.wood.indices.insert(tree.wood.indices.end(),
                             {base, base + 1, base + 2, base + 1, base + 3, base + 2});
    tree.wood.materialIds.insert(tree.wood.materialIds.end(), {0, 0});
  };
  addSegment({0, 0, 0}, {0, 4, 0});         // trunk
  addSegment({0.05f, 1, 0}, {2, 2, 0});     // lower branch, starting on the trunk
  addSegment({2.05f, 2.1f, 0}, {3, 4, 0});  // twig, starting at the lower branch's tip
  Leaf leaf = tree.leaves[0];
  leaf.branch = -1;
  std::vector<Leaf> leaves;
  for (const glm::vec3& c :
       {glm::vec3(0.1f, 3.5f, 0.1f), glm::vec3(1.5f, 1.8f, 0.1f), glm::vec3(2.9f, 3.9f, 0.1f)}) {
    leaf.center = c;
    leaves.push_back(leaf);
  }
  tree.leaves = leaves;
  finalizeTree(tree, "wood parts");
  const BoxHierarchy h = woodHierarchy(tree);
  ASSERT_EQ(h.nodes.size(), 3u);
  EXPECT_EQ(h.source, "wood");
  EXPECT_EQ(h.nodes[0].parent, -1);
  EXPECT_EQ(h.nodes[1].parent, 0);  // the lower branch on the trunk
  EXPECT_EQ(h.nodes[2].parent, 1);  // the twig on the lower branch, not on the trunk
  EXPECT_EQ(h.nodes[2].level, 2);
  // Each leaf on its nearest part; the root's range holds all three.
  EXPECT_EQ(h.leafOrder[h.nodes[0].leafBegin], 0u);
  EXPECT_EQ(h.leafOrder[h.nodes[1].leafBegin], 1u);
  EXPECT_EQ(h.leafOrder[h.nodes[2].leafBegin], 2u);
  EXPECT_EQ(h.nodes[0].subtreeLeafEnd - h.nodes[0].leafBegin, 3u);
  EXPECT_TRUE(h.nodes[0].box.contains(h.nodes[2].box));
  // One connected part: no hierarchy from the wood.
  tree.wood.indices.insert(tree.wood.indices.end(), {0, 4, 8});
  tree.wood.materialIds.push_back(0);
  EXPECT_TRUE(woodHierarchy(tree).nodes.empty());
}

TEST(BoxHierarchy, VolumeRatioPruningKeepsTheRootAndPrunesSmallBoxes) {
  const Tree tree = test::smallTree(1200, 3);
  BoxHierarchy h = hierarchyFromBranches(tree);
  pruneByVolumeRatio(h, 1.0f);  // no child is as big as its parent
  EXPECT_TRUE(h.nodes[0].textured);
  for (size_t n = 1; n < h.nodes.size(); ++n) {
    const float ratio = h.nodes[n].box.volume() / h.nodes[h.nodes[n].parent].box.volume();
    EXPECT_EQ(h.nodes[n].textured,
              ratio >= 1.0f && h.nodes[n].subtreeLeafEnd > h.nodes[n].leafBegin);
  }
  pruneByVolumeRatio(h, 0.0f);
  size_t textured = 0;
  for (const BoxNode& n : h.nodes) textured += n.textured;
  EXPECT_GT(textured, 1u);
  pruneByVolumeRatio(h, 0.0f, 40);  // boxes with fewer than 40 leaves get no images
  for (const BoxNode& n : h.nodes) EXPECT_EQ(n.textured, n.subtreeLeafEnd - n.leafBegin >= 40);
  EXPECT_TRUE(h.nodes[0].textured);
}

TEST(BoxHierarchy, KeepingFewerTexturedBoxesDropsTheFinestFirst) {
  const Tree tree = test::smallTree(1200, 3);
  BoxHierarchy h = hierarchyFromBranches(tree);
  pruneByVolumeRatio(h, 0.0f);
  const std::vector<int32_t> order = texturedCoarseToFine(h);
  ASSERT_GT(order.size(), 4u);
  EXPECT_EQ(order[0], 0) << "the root first";
  for (size_t i = 1; i < order.size(); ++i) {
    const BoxNode &a = h.nodes[order[i - 1]], &b = h.nodes[order[i]];
    EXPECT_TRUE(a.level < b.level || (a.level == b.level && a.subtreeLeafEnd - a.leafBegin >=
                                                                b.subtreeLeafEnd - b.leafBegin));
  }
  const size_t keep = order.size() / 2;
  keepTexturedBoxes(h, keep);
  for (size_t i = 0; i < order.size(); ++i) EXPECT_EQ(h.nodes[order[i]].textured, i < keep);
  keepTexturedBoxes(h, 0);  // the root keeps its images whatever the bound
  EXPECT_TRUE(h.nodes[0].textured);
  EXPECT_EQ(texturedCoarseToFine(h).size(), 1u);
}

// Each leaf's drawn share summed over the walk's entries: a box counts for every leaf of its
// subtree, a leaf node for its own leaves; a dissolved entry for the dither range it keeps.
std::vector<float> drawnShares(const Tree& tree, const BoxHierarchy& h, const HierarchyWalk& walk) {
  std::vector<float> drawn(tree.leaves.size(), 0.0f);
  for (const WalkEntry& entry : walk.boxes) {
    EXPECT_TRUE(h.nodes[entry.node].textured);
    for (uint32_t i = h.nodes[entry.node].leafBegin; i < h.nodes[entry.node].subtreeLeafEnd; ++i)
      drawn[h.leafOrder[i]] += entry.share();
  }
  for (const WalkEntry& entry : walk.leafNodes) {
    for (uint32_t i = h.nodes[entry.node].leafBegin; i < h.nodes[entry.node].leafEnd; ++i)
      drawn[h.leafOrder[i]] += entry.share();
  }
  return drawn;
}

// The walk from a viewer `distance` bounding radii from the tree's centre along one oblique
// direction, each box's LoD distance three times its diagonal.
HierarchyWalk walkFrom(const Tree& tree, const BoxHierarchy& h, float distance, float transition) {
  std::vector<float> lod(h.nodes.size());
  for (size_t n = 0; n < lod.size(); ++n) lod[n] = 3.0f * glm::length(h.nodes[n].box.extent());
  const glm::vec3 viewer =
      tree.bounds.center() + glm::vec3(0.3f, 0.2f, 1.0f) * distance * tree.boundingSphereRadius();
  HierarchyWalk walk;
  walkHierarchy(h, lod, viewer, transition, -1, walk);
  return walk;
}

TEST(BoxHierarchy, TheWalkDrawsEveryLeafExactlyOnceAtAnyDistance) {
  const Tree tree = test::smallTree(1200, 3);
  for (BoxHierarchy h : hierarchiesOf(tree)) {
    pruneByVolumeRatio(h, 0.05f);
    for (float distance : {0.0f, 0.5f, 2.0f, 5.0f, 10.0f, 30.0f, 1000.0f}) {
      const HierarchyWalk walk = walkFrom(tree, h, distance, 0.0f);
      const std::vector<float> drawn = drawnShares(tree, h, walk);
      for (size_t l = 0; l < drawn.size(); ++l)
        ASSERT_EQ(drawn[l], 1.0f) << h.source << " distance " << distance << " leaf " << l;
      if (distance >= 1000.0f) {
        ASSERT_EQ(walk.boxes.size(), 1u);
        EXPECT_EQ(walk.boxes[0].node, 0) << "far away: the root's images only";
      }
      if (distance == 0.0f) {
        EXPECT_FALSE(walk.leafNodes.empty()) << "inside the tree: nearby leaves as polygons";
      }
    }
  }
}

// With a transition band, boxes in it are drawn on part of the pixels and their finer level on
// the rest: every leaf's shares still add up to one, and some distances do dissolve.
TEST(BoxHierarchy, TransitionBandsSplitEachLeafsPixelsBetweenTwoLevels) {
  const Tree tree = test::smallTree(1200, 3);
  for (BoxHierarchy h : hierarchiesOf(tree)) {
    pruneByVolumeRatio(h, 0.05f);
    int dissolvedWalks = 0;
    for (int step = 0; step <= 60; ++step) {
      const float distance = 0.25f * float(step);
      const HierarchyWalk walk = walkFrom(tree, h, distance, 0.5f);
      const std::vector<float> drawn = drawnShares(tree, h, walk);
      for (size_t l = 0; l < drawn.size(); ++l)
        ASSERT_NEAR(drawn[l], 1.0f, 1e-5f) << h.source << " distance " << distance << " leaf " << l;
      const auto dissolved = [](const WalkEntry& e) { return e.threshold > 0.0f; };
      if (std::any_of(walk.boxes.begin(), walk.boxes.end(), dissolved)) ++dissolvedWalks;
    }
    EXPECT_GT(dissolvedWalks, 0) << h.source << ": no distance fell in a transition band";
  }
}

// Forcing a level draws the textured boxes of that level (or finer, where that level's box has
// no images) as images, whatever the distance, and still every leaf once.
TEST(BoxHierarchy, AForcedLevelDrawsThatLevelsBoxesAtAnyDistance) {
  const Tree tree = test::smallTree(1200, 3);
  for (BoxHierarchy h : hierarchiesOf(tree)) {
    pruneByVolumeRatio(h, 0.05f);
    const std::vector<float> lod(h.nodes.size(), 1e9f);  // never far enough on its own
    HierarchyWalk walk;
    walkHierarchy(h, lod, tree.bounds.center(), 0.25f, 1, walk);
    const std::vector<float> drawn = drawnShares(tree, h, walk);
    for (size_t l = 0; l < drawn.size(); ++l)
      ASSERT_EQ(drawn[l], 1.0f) << h.source << " leaf " << l;
    for (const WalkEntry& entry : walk.boxes) EXPECT_GE(h.nodes[entry.node].level, 1);
  }
}

// A sparse tree of large leaves, so they cover several pixels where the root box is drawn as
// its images.
Tree largeLeafTree() {
  LSystemTreeParams params = treePreset("sparse");
  params.leaves = 300;
  params.leafLength = 0.9f;
  params.leafWidth = 0.5f;
  params.leafTextureSize = 64;
  return generateTree(params, 3);
}

// A narrow camera looking at the tree's centre from `direction`, far enough (20 radii) that the
// root box is drawn as its images.
Camera farCamera(const Tree& tree, const glm::vec3& direction, float fovYDegrees) {
  const float radius = tree.boundingSphereRadius();
  Camera camera;
  camera.target = tree.bounds.center();
  camera.position = camera.target + glm::normalize(direction) * (radius * 20.0f);
  camera.fovYDegrees = fovYDegrees;
  camera.nearPlane = radius * 15.0f;
  camera.farPlane = radius * 25.0f;
  return camera;
}

// A box image seen along its face direction matches the polygonal leaves inside the box.
TEST(BboxHierarchy, BoxImageMatchesTheLeavesInsideTheBox) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = largeLeafTree();
  RenderSettings settings;
  settings.width = settings.height = 96;
  settings.fovYDegrees = 10.0f;
  Harness harness(device, settings);
  const Camera camera = farCamera(tree, {0, 0, 1}, settings.fovYDegrees);  // along +Z
  const auto render = [&](const std::string& name, const nlohmann::json& params) {
    return harness.render(*test::bakeAndUpload(device, tree, name, params), camera);
  };
  // Only the root has images (volume ratio 1), about one texel per pixel of the view.
  const ImageRgba8 reference = render("polygonal", {{"wood", false}});
  const ImageRgba8 boxes =
      render("bbox_hierarchy",
             {{"wood", false}, {"texture_size", 128}, {"transition", 0.0}, {"volume_ratio", 1.0}});
  const ImageMetrics metrics = compareImages(reference, boxes);
  if (std::getenv("CANOPY_DUMP")) {
    writePng("/tmp/cb/box_ref.png", withOpaqueAlpha(reference));
    writePng("/tmp/cb/box_img.png", withOpaqueAlpha(boxes));
  }
  std::printf("root box image vs its leaves: PSNR %.2f dB, SSIM %.3f, coverage error %.4f\n",
              metrics.psnr, metrics.ssim, metrics.coverageError);
  // Floor: the capture is orthographic onto the plane through the box centre, the view a narrow
  // perspective (10°): differences come from resampling and from the leaves' depth spread
  // (parallax of up to a few pixels at the frame's edge). Measured here: 21.1 dB, SSIM 0.85,
  // coverage error 0.15; the floors leave about 3 dB and 0.15 SSIM for other drivers' filtering,
  // while a misplaced or mirrored image loses the structure SSIM measures.
  EXPECT_GT(metrics.psnr, 18.0);
  EXPECT_GT(metrics.ssim, 0.7);
  EXPECT_LT(metrics.coverageError, 0.25);
}

// The facing blend (§4): seen obliquely, a box's less squarely facing quad keeps the share
// w / w_max of its pixels. Seen 25° off the +Z face, the X quad's weight is tan 25° = 0.47 of the
// Z quad's, so of the coverage only the X quad adds, the blend keeps about that share; a large
// facing_power keeps almost none of it, and no blending keeps all of it.
TEST(BboxHierarchy, FacingBlendFadesTheObliqueQuadByItsWeight) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = largeLeafTree();
  RenderSettings settings;
  settings.width = settings.height = 320;  // the root's 256² texels still one per pixel or less
  settings.fovYDegrees = 10.0f;
  Harness harness(device, settings);
  const float azimuth = glm::radians(25.0f);
  const Camera camera =
      farCamera(tree, {std::sin(azimuth), 0.0f, std::cos(azimuth)}, settings.fovYDegrees);
  const auto coverage = [&](const nlohmann::json& blend) {
    nlohmann::json p = {
        {"wood", false}, {"texture_size", 256}, {"transition", 0.0}, {"volume_ratio", 1.0}};
    p.update(blend);
    const ImageRgba8 image =
        harness.render(*test::bakeAndUpload(device, tree, "bbox_hierarchy", p), camera);
    double sum = 0.0;
    for (size_t i = 3; i < image.pixels.size(); i += 4) sum += image.pixels[i] / 255.0;
    return sum;
  };
  const double all = coverage({{"quad_blend", "none"}});
  const double blended = coverage({{"quad_blend", "facing"}, {"facing_power", 1.0}});
  const double frontOnly = coverage({{"quad_blend", "facing"}, {"facing_power", 16.0}});
  const double kept = (blended - frontOnly) / (all - frontOnly);
  std::printf("coverage (pixel units): none %.1f, facing %.1f, facing^16 %.1f; kept share %.3f\n",
              all, blended, frontOnly, kept);
  ASSERT_GT(all - frontOnly, 300.0) << "the X quad adds coverage of its own at this view";
  // tan 25° = 0.466, power 16 keeps 0.466^16 ≈ 0 of its pixels; the dither is uniform, so the kept
  // share is the weight up to sampling and to pixels both quads share after filtering (±0.15).
  EXPECT_NEAR(kept, std::tan(azimuth), 0.15);
}

// lod_bias > 1 switches boxes to their images nearer the viewer: fewer leaf polygons.
TEST(BboxHierarchy, LodBiasDrawsImagesNearer) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = test::smallTree(1200, 3);
  RenderSettings settings;
  settings.width = settings.height = 128;
  Harness harness(device, settings);
  Camera camera;
  camera.target = tree.bounds.center();
  camera.position = camera.target + glm::vec3(0, 0, 1) * (tree.boundingSphereRadius() * 2.0f);
  std::map<float, uint64_t> leafPolygons;
  for (const float bias : {1.0f, 4.0f}) {
    auto method = test::bakeAndUpload(
        device, tree, "bbox_hierarchy",
        {{"wood", false}, {"lod_bias", bias}, {"min_box_leaves", 4}, {"volume_ratio", 0.0}});
    harness.render(*method, camera);
    leafPolygons[bias] = method->leafPolygonsDrawn();
  }
  std::printf("leaf polygons drawn: lod_bias 1: %llu, 4: %llu\n",
              (unsigned long long)leafPolygons[1.0f], (unsigned long long)leafPolygons[4.0f]);
  EXPECT_GT(leafPolygons[1.0f], 0u);
  EXPECT_LT(leafPolygons[4.0f], leafPolygons[1.0f]);
}

// The box images fit texture_budget_mb whatever the tree: a tree with eight times the leaves has
// more boxes worth images, and under the bound its finest boxes lose theirs, so its texture memory
// (ledger) stays that of the small tree, while without one it grows with the leaves.
TEST(BboxHierarchy, TextureMemoryDoesNotGrowWithTheLeavesUnderTheBudget) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  LSystemTreeParams params = treePreset("broadleaf");
  params.leafTextureSize = 32;
  const double budgetMb = 0.3;  // below what either tree's boxes would take
  std::map<int, uint64_t> bounded, unbounded;
  for (const int leaves : {1000, 8000}) {
    params.leaves = leaves;
    const Tree tree = generateTree(params, 1);
    for (const double budget : {0.0, budgetMb}) {
      const std::string owner = "bbox " + std::to_string(leaves) + " " + std::to_string(budget);
      auto method = test::bakeAndUpload(device, tree, "bbox_hierarchy",
                                        {{"wood", false}, {"texture_budget_mb", budget}},
                                        Shading::kUnlit, owner);
      (budget > 0.0 ? bounded : unbounded)[leaves] = ledger.totals(owner).texture;
      const nlohmann::json report = method->bakeReport();
      if (budget > 0.0) {
        EXPECT_GT(report["boxes_over_texture_budget"].get<int>(), 0) << leaves << " leaves";
        // BC3: one byte a texel, a third more for the mip levels.
        const double atlasBytes =
            report["atlas"][0].get<double>() * report["atlas"][1].get<double>() * 4.0 / 3.0;
        EXPECT_LE(atlasBytes, budget * 1e6) << leaves << " leaves";
      } else {
        EXPECT_EQ(report["boxes_over_texture_budget"].get<int>(), 0);
      }
    }
  }
  std::printf("texture bytes, 1000 / 8000 leaves: %llu / %llu unbounded, %llu / %llu bounded\n",
              (unsigned long long)unbounded[1000], (unsigned long long)unbounded[8000],
              (unsigned long long)bounded[1000], (unsigned long long)bounded[8000]);
  EXPECT_GT(unbounded[8000], 2 * unbounded[1000]);
  // The same leaf images and an atlas of the same bound: within the packing's slack.
  EXPECT_LT(double(bounded[8000]), 1.25 * double(bounded[1000]));
}

// wood_capture: the root box's images hold the wood, and a tree drawn with the root box alone
// draws none as geometry (its wood level is the empty residual chain). Far away the captured wood
// shows: on a tree of few leaves, whose wood is much of its coverage, the coverage against the
// reference is closer than with the wood left out (measured 0.40 against 0.49). Nearer, where
// finer boxes and the wood's geometry are drawn, the image is the one without capture.
TEST(BboxHierarchy, WoodCaptureDrawsAFarTreesWoodFromTheRootImagesOnly) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = test::smallTree(100, 5);
  ASSERT_GT(tree.wood.triangleCount(), 0u);
  RenderSettings settings;
  settings.width = settings.height = 256;
  Harness harness(device, settings);
  const float focal =
      0.5f * float(settings.height) / std::tan(glm::radians(0.5f * settings.fovYDegrees));
  const float radius = 0.5f * glm::length(tree.bounds.extent());
  const auto cameraAt = [&](float projectedRadius) {
    Camera camera;
    camera.fovYDegrees = settings.fovYDegrees;
    camera.target = tree.bounds.center();
    const float distance = radius * focal / projectedRadius;
    camera.position = camera.target + glm::normalize(glm::vec3(0.6f, 0.3f, 0.74f)) * distance;
    camera.farPlane = distance + 2.0f * radius;
    return camera;
  };
  const nlohmann::json base = {{"texture_size", 64}, {"wood_capture", true}};
  auto captured = test::bakeAndUpload(device, tree, "bbox_hierarchy", base);
  nlohmann::json off = base;
  off["wood_capture"] = false;
  auto geometry = test::bakeAndUpload(device, tree, "bbox_hierarchy", off);
  nlohmann::json none = base;
  none["wood"] = false;  // wood_capture is then false in effect
  auto woodless = test::bakeAndUpload(device, tree, "bbox_hierarchy", none);
  auto reference = test::bakeAndUpload(device, tree, "polygonal", {});
  const float below = captured->bakeReport()["wood_captured"]["root_only_below_px"].get<float>();
  EXPECT_EQ(captured->bakeReport()["wood_captured"]["triangles"].get<size_t>(),
            tree.wood.triangleCount());
  EXPECT_EQ(geometry->bakeReport()["wood_captured"]["triangles"].get<size_t>(), 0u);
  EXPECT_EQ(geometry->effectiveParams()["wood_capture"], false);
  EXPECT_EQ(woodless->effectiveParams()["wood_capture"], false);  // no wood to capture
  ASSERT_GT(below, 4.0f);

  // Far: the triangles of the wood level drawn, with and without capture.
  const auto woodTrianglesDrawn = [&](Method& method) {
    const nlohmann::json levels = method.bakeReport()["wood_levels"];
    const std::vector<uint64_t> instances = method.woodInstancesPerLevel();
    uint64_t triangles = 0;
    for (size_t l = 0; l < instances.size(); ++l)
      triangles += instances[l] * levels[l]["triangles"].get<uint64_t>();
    return triangles;
  };
  const Camera far = cameraAt(0.8f * below);
  const ImageRgba8 referenceFar = harness.render(*reference, far);
  const ImageMetrics withCapture = compareImages(referenceFar, harness.render(*captured, far));
  EXPECT_EQ(woodTrianglesDrawn(*captured), 0u);
  harness.render(*geometry, far);
  EXPECT_GT(woodTrianglesDrawn(*geometry), 0u);
  const ImageMetrics withoutWood = compareImages(referenceFar, harness.render(*woodless, far));
  std::printf(
      "far tree (%.1f px radius, root only below %.1f): coverage error %.4f with the wood "
      "in the images, %.4f with no wood\n",
      0.8f * below, below, withCapture.coverageError, withoutWood.coverageError);
  EXPECT_LT(withCapture.coverageError, withoutWood.coverageError);

  // Near: finer boxes and the wood as geometry, the same image either way but for the atlas'
  // mip levels, whose alpha scale is one per level over all boxes (the root's images changed).
  const Camera near = cameraAt(3.0f * below);
  const ImageMetrics nearMetrics =
      compareImages(harness.render(*geometry, near), harness.render(*captured, near));
  EXPECT_GT(woodTrianglesDrawn(*captured), 0u);
  std::printf("near tree: PSNR %.2f dB, coverage error %.5f between capture and none\n",
              nearMetrics.psnr, nearMetrics.coverageError);
  EXPECT_GT(nearMetrics.psnr, 40.0);
}

TEST(BboxHierarchy, BadParametersNameTheParameter) {
  test::expectParameterErrorsNameTheKey("bbox_hierarchy", {{"texture_size", 0},
                                                           {"volume_ratio", 2.0},
                                                           {"arrangement", "star"},
                                                           {"hierarchy", "octree"},
                                                           {"transition", -1.0},
                                                           {"compression", "bc7"},
                                                           {"texture_budget_mb", -1.0},
                                                           {"quad_blend", "sorted"},
                                                           {"facing_power", 0.0},
                                                           {"lod_bias", 0.0},
                                                           {"wood_capture", 2}});
}

}  // namespace
}  // namespace canopy
