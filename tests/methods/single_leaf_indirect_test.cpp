#include "methods/single_leaf_indirect/single_leaf_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "methods/common/leaf_orientations.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

TEST(SingleLeafGrid, EachCellHoldsAtMostTheFrontmostLeafCentredInIt) {
  const Tree tree = test::smallTree(1500, 9);
  ClusteringParams params;
  params.clusters = 40;
  const BillboardCloud cloud = buildBillboardCloud(tree, params, 2);
  const OrientationBins bins;
  const float cellLength = meanLeafLength(tree);
  const auto grids = buildSingleLeafGrids(tree, cloud, cellLength, bins, 1024);
  ASSERT_EQ(grids.size(), cloud.billboards.size());
  size_t shown = 0;
  for (size_t b = 0; b < grids.size(); ++b) {
    const Billboard& billboard = cloud.billboards[b];
    const SingleLeafGrid& grid = grids[b];
    ASSERT_EQ(grid.leaf.size(), size_t(grid.cells.x) * grid.cells.y);
    // Expected winner per cell, computed independently: the front-most centre in the cell.
    std::vector<float> front(grid.leaf.size(), std::numeric_limits<float>::lowest());
    std::vector<int32_t> expected(grid.leaf.size(), -1);
    for (uint32_t index : billboard.leaves) {
      const glm::vec2 p = billboard.toPlane(tree.leaves[index].center);
      const glm::vec2 cellSize = 2.0f * billboard.halfExtents / glm::vec2(grid.cells);
      const int cx = std::clamp(int(std::floor((p.x + billboard.halfExtents.x) / cellSize.x)), 0,
                                grid.cells.x - 1);
      const int cy = std::clamp(int(std::floor((p.y + billboard.halfExtents.y) / cellSize.y)), 0,
                                grid.cells.y - 1);
      const size_t cell = size_t(cy) * grid.cells.x + cx;
      const float height = glm::dot(tree.leaves[index].center - billboard.center, billboard.normal);
      if (height > front[cell]) front[cell] = height, expected[cell] = int32_t(index);
    }
    EXPECT_EQ(grid.leaf, expected) << "billboard " << b;
    for (size_t cell = 0; cell < grid.leaf.size(); ++cell) {
      if (grid.leaf[cell] < 0) continue;
      ++shown;
      EXPECT_EQ(grid.image[cell],
                orientedImageIndex(tree.leaves[grid.leaf[cell]], billboard, bins));
    }
  }
  // One leaf per cell drops the leaves that share a cell: fewer shown than the tree has.
  EXPECT_LT(shown, tree.leaves.size());
  EXPECT_GT(shown, tree.leaves.size() / 4);
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
                                                                 {"clusters", 0}});
}

}  // namespace
}  // namespace canopy
