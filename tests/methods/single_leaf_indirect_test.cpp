#include "methods/single_leaf_indirect/single_leaf_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "methods/common/cloud_levels.h"
#include "methods/common/leaf_orientations.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

TEST(SingleLeafGrid, EveryLeafHasACellOfItsOwnNearItsCentre) {
  const Tree tree = test::smallTree(1500, 9);
  ClusteringParams params;
  params.clusters = 40;
  const BillboardCloud cloud = buildBillboardCloud(tree, params, 2);
  const OrientationBins bins;
  const float cellLength = meanLeafLength(tree);
  for (const float cells : {1.0f, 3.0f}) {  // a coarse grid makes leaves crowd: cells halve
    const auto grids = buildSingleLeafGrids(tree, cloud, cells * cellLength, bins, 1024);
    ASSERT_EQ(grids.size(), cloud.billboards.size());
    size_t placed = 0, halved = 0;
    for (size_t b = 0; b < grids.size(); ++b) {
      const Billboard& billboard = cloud.billboards[b];
      const SingleLeafGrid& grid = grids[b];
      ASSERT_EQ(grid.leaf.size(), size_t(grid.cells.x) * grid.cells.y);
      halved += grid.cellLength < 0.75f * cells * cellLength;
      std::vector<int> seen(tree.leaves.size(), 0);
      const glm::vec2 cellSize = 2.0f * billboard.halfExtents / glm::vec2(grid.cells);
      for (size_t cell = 0; cell < grid.leaf.size(); ++cell) {
        if (grid.leaf[cell] < 0) continue;
        const Leaf& leaf = tree.leaves[size_t(grid.leaf[cell])];
        ++seen[size_t(grid.leaf[cell])];
        ++placed;
        // Independently: the cell that holds the leaf's projected centre, and the distance.
        const glm::vec2 p = (billboard.toPlane(leaf.center) + billboard.halfExtents) / cellSize;
        const glm::ivec2 home =
            glm::clamp(glm::ivec2(glm::floor(p)), glm::ivec2(0), grid.cells - 1);
        const glm::ivec2 at(int(cell % grid.cells.x), int(cell / grid.cells.x));
        EXPECT_LE(std::max(std::abs(at.x - home.x), std::abs(at.y - home.y)), kSearchRadius);
        EXPECT_EQ(grid.image[cell], orientedImageIndex(leaf, billboard, bins));
        // The image keeps the leaf's own size whatever the cell size.
        EXPECT_NEAR(grid.scale[cell] * grid.cellLength,
                    2.0f * std::max(leaf.halfExtents.x, leaf.halfExtents.y), 1e-5f);
      }
      for (uint32_t index : billboard.leaves) EXPECT_EQ(seen[index], 1) << "leaf " << index;
      EXPECT_EQ(grid.leavesPlaced, billboard.leaves.size());
    }
    EXPECT_EQ(placed, tree.leaves.size()) << "every leaf is shown";
    if (cells == 3.0f) {
      EXPECT_GT(halved, 0u) << "crowded billboards halve their cells";
    }
  }
}

// A small tree seen at 128² from 2 radii, 20° up: the image tests' setting (they turn its
// wood off).
class SingleLeafImages : public ::testing::Test {
 protected:
  static RenderSettings smallFrame() {
    RenderSettings settings;
    settings.width = settings.height = 128;
    return settings;
  }
  const Tree tree = test::smallTree(800, 4);
  std::unique_ptr<gl::Context> context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device{ledger};
  Harness harness{device, smallFrame()};
  const Camera camera = orbitCamera(tree.bounds, {2.0f, 20.0f, 40.0f}, 40.0f);
};

TEST_F(SingleLeafImages, ShowsEveryLeafAndKeepsLeafSizeWhateverTheCellSize) {
  // Bake report and image: the same tree at two cell sizes covers about as much of the frame
  // (leaves keep their size), and every leaf is represented. The cell lookup, which draws the
  // leaves: at 128² the tree spans fewer pixels than lod_lowres_px, whose texture would draw
  // each cell's coverage instead (hashed, so a coarser cell grid covers more).
  std::vector<long> covered;
  for (const double cellSize : {0.5, 2.0}) {
    auto method = test::bakeAndUpload(
        device, tree, "single_leaf_indirect",
        {{"cell_size", cellSize}, {"lod", false}, {"lod_lowres_px", 0}, {"wood", false}},
        Shading::kUnlit, "cells " + std::to_string(cellSize));
    EXPECT_EQ(method->bakeReport().at("leaves_represented").get<size_t>(), tree.leaves.size());
    const ImageRgba8 image = harness.render(*method, camera);
    long count = 0;
    for (size_t i = 3; i < image.pixels.size(); i += 4) count += image.pixels[i] >= 128;
    covered.push_back(count);
  }
  ASSERT_GT(covered[0], 500);
  EXPECT_NEAR(double(covered[1]) / double(covered[0]), 1.0, 0.25);
}

TEST(ShaderLodLevels, SplitsTheCloudAtTheTextureThresholdAndKeepsLookupsFirst) {
  CloudLevels clouds;
  clouds.addLevel(0, 10);  // near: billboards 0–9
  clouds.addLevel(10, 4);  // middle
  clouds.addLevel(14, 2);  // far
  const std::vector<float> thresholds = {120.0f, 35.0f};
  const auto firsts = [](const ShaderLodLevels& levels) {
    std::vector<uint32_t> out;
    for (const CloudLevels::Range& range : levels.draw.ranges) out.push_back(range.first / 6);
    return out;
  };
  const ShaderLodLevels none = shaderLodLevels(clouds, thresholds, 0.0f);
  EXPECT_EQ(none.thresholds, thresholds);
  EXPECT_EQ(none.lookupLevels, 3u);
  EXPECT_EQ(none.firstTextureCloud, 3u);
  EXPECT_EQ(firsts(none), (std::vector<uint32_t>{0, 10, 14}));

  const ShaderLodLevels middle = shaderLodLevels(clouds, thresholds, 90.0f);
  EXPECT_EQ(middle.thresholds, (std::vector<float>{120.0f, 90.0f, 35.0f}));
  EXPECT_EQ(middle.lookupLevels, 2u);  // near and middle looked up above 90 px
  EXPECT_EQ(middle.firstTextureCloud, 1u);
  EXPECT_EQ(firsts(middle), (std::vector<uint32_t>{0, 10, 10, 14}));

  const ShaderLodLevels atFar = shaderLodLevels(clouds, thresholds, 35.0f);
  EXPECT_EQ(atFar.thresholds, thresholds);
  EXPECT_EQ(atFar.lookupLevels, 2u);
  EXPECT_EQ(atFar.firstTextureCloud, 2u);

  const ShaderLodLevels aboveNear = shaderLodLevels(clouds, thresholds, 200.0f);
  EXPECT_EQ(aboveNear.thresholds, (std::vector<float>{200.0f, 120.0f, 35.0f}));
  EXPECT_EQ(aboveNear.lookupLevels, 1u);
  EXPECT_EQ(aboveNear.firstTextureCloud, 0u);
  EXPECT_EQ(firsts(aboveNear), (std::vector<uint32_t>{0, 0, 10, 14}));
  // Every radius draws the cloud it drew without textures.
  for (const float radius : {500.0f, 150.0f, 100.0f, 50.0f, 10.0f}) {
    const int cloud = LodInstances::levelFor(radius, thresholds);
    const int level = LodInstances::levelFor(radius, aboveNear.thresholds);
    EXPECT_EQ(aboveNear.draw.ranges[size_t(level)].first, clouds.ranges[size_t(cloud)].first)
        << radius;
    EXPECT_EQ(size_t(level) >= aboveNear.lookupLevels, radius < 200.0f) << radius;
  }
}

TEST_F(SingleLeafImages, LowResolutionTextureShowsWhatTheLookupShows) {
  // lod_lowres_px above any projected size draws every tree as the texture, captured from the
  // leaves themselves: coverage near the reference's (magnified texels round the leaves off; in
  // development runs 0.79 of it) and no farther from it than the lookup's (0.53: the regular
  // pattern loses leaf overlap), about the lookup's colour, through another path.
  std::vector<ImageRgba8> images;
  for (const double lowResPixels : {0.0, 100000.0}) {
    auto method =
        test::bakeAndUpload(device, tree, "single_leaf_indirect",
                            {{"lod_lowres_px", lowResPixels}, {"lod", false}, {"wood", false}},
                            Shading::kUnlit, "lowres " + std::to_string(lowResPixels));
    const auto atlas = method->bakeReport().at("lowres_atlas");
    EXPECT_EQ(atlas[0].get<int>() > 0, lowResPixels > 0.0);
    images.push_back(harness.render(*method, camera));
  }
  auto reference = test::bakeAndUpload(device, tree, "polygonal", {{"wood", false}},
                                       Shading::kUnlit, "reference");
  images.push_back(harness.render(*reference, camera));
  long covered[3] = {0, 0, 0}, differing = 0;
  double green[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < images[0].pixels.size(); i += 4) {
    for (int k = 0; k < 3; ++k) {
      if (images[size_t(k)].pixels[i + 3] < 128) continue;
      ++covered[k];
      green[k] += images[size_t(k)].pixels[i + 1];
    }
    differing += images[0].pixels[i + 3] != images[1].pixels[i + 3] ||
                 images[0].pixels[i + 1] != images[1].pixels[i + 1];
  }
  ASSERT_GT(covered[2], 500);
  ASSERT_GT(covered[0], 0);
  ASSERT_GT(covered[1], 0);
  EXPECT_NEAR(double(covered[1]) / double(covered[2]), 0.9, 0.25);
  EXPECT_LE(std::abs(covered[1] - covered[2]), std::abs(covered[0] - covered[2]));
  EXPECT_NEAR(green[1] / double(covered[1]), green[0] / double(covered[0]), 25.0);
  EXPECT_GT(differing, 0) << "the texture path drew the lookup's image";
}

TEST(LeafOrientations, IndexEncodesRotationTiltAndSide) {
  Billboard billboard;
  billboard.normal = {0, 0, 1};
  billboard.axisU = {1, 0, 0};
  billboard.axisV = {0, 1, 0};
  Leaf leaf;
  leaf.normal = {0, 0, 1};
  leaf.axisU = {0, -1, 0};
  leaf.axisV = {1, 0, 0};  // the leaf's axis along the billboard's u: rotation 0
  const OrientationBins bins{8, 2};
  EXPECT_EQ(orientedImageIndex(leaf, billboard, bins),
            (0u * 2 + 1) * 8 + 0);  // face-on: widest tilt
  leaf.axisV = {0, 1, 0};           // 90°: rotation 2 of 8
  leaf.axisU = {1, 0, 0};
  EXPECT_EQ(orientedImageIndex(leaf, billboard, bins), 1u * 8 + 2);
  leaf.normal = glm::normalize(glm::vec3(0.9f, 0, 0.3f));  // steep: foreshortened, narrow tilt bin
  EXPECT_EQ(orientedImageIndex(leaf, billboard, bins), 0u * 8 + 2);
  leaf.normal = {0, 0, -1};  // turned away: back images
  leaf.texture = 1;
  EXPECT_EQ(orientedImageIndex(leaf, billboard, bins), ((1u * 2 + 1) * 2 + 1) * 8 + 2);
  EXPECT_EQ(orientedImageCount(2, bins), 64u);
}

TEST(LeafOrientations, QuarterTurnImagesAreRotationsOfEachOther) {
  const Tree tree = test::smallTree(50);
  const LeafImageSampler sampler(tree);
  const OrientationBins bins{4, 1};
  const auto images = buildOrientedLeafImages(tree, sampler, bins, 32);
  ASSERT_EQ(images.size(), orientedImageCount(tree.leafTextures.size(), bins));
  // Rotation 1 is rotation 0 turned by 90°: compare coverage pixel by pixel.
  int agree = 0, covered = 0;
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      const bool a = images[0].at(x, y)[3] >= 128;
      const bool b = images[1].at(31 - y, x)[3] >= 128;
      covered += a;
      agree += a == b;
    }
  }
  EXPECT_GT(covered, 32 * 32 / 8);
  EXPECT_GT(agree, 32 * 32 * 95 / 100);
}

TEST(SingleLeafIndirect, BadParametersNameTheParameter) {
  test::expectParameterErrorsNameTheKey("single_leaf_indirect", {{"cell_size", 0.0},
                                                                 {"rotations", 0},
                                                                 {"tilts", 0},
                                                                 {"leaf_image_size", 2},
                                                                 {"clusters", 0},
                                                                 {"view_orders", -1},
                                                                 {"lod_lowres_px", -1.0},
                                                                 {"lowres_texels_per_cell", 0}});
}

}  // namespace
}  // namespace canopy
