#include "methods/common/ambient_occlusion.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace canopy {
namespace {

TEST(AmbientOcclusion, AnOccluderDarkensTheLeafBelowIt) {
  Tree tree = test::smallTree(50);
  Leaf open = tree.leaves[0];
  open.center = {0, 0, 0};
  open.normal = {0, 1, 0};
  open.axisU = {1, 0, 0};
  open.axisV = {0, 0, -1};
  open.halfExtents = {0.05f, 0.05f};
  open.uvMin = {0.45f, 0.45f};  // the opaque middle of the blade: an opaque card
  open.uvMax = {0.55f, 0.55f};
  open.branch = -1;
  Leaf covered = open;
  covered.center = {10, 0, 0};
  Leaf roof = covered;  // a big opaque card just above the covered leaf
  roof.center = {10, 0.05f, 0};
  roof.halfExtents = {1.0f, 1.0f};
  tree.leaves = {open, covered, roof};
  tree.branches.clear();
  tree.wood = {};
  tree.woodMaterials.clear();
  finalizeTree(tree, "ao");
  const auto ao = computeLeafCornerOcclusion(tree, 256, 1);
  for (int c = 0; c < 4; ++c) {
    EXPECT_GT(ao[0][c], 0.97f);         // nothing near: open everywhere
    EXPECT_NEAR(ao[1][c], 0.5f, 0.1f);  // the upper hemisphere is blocked
  }
  EXPECT_EQ(ao, computeLeafCornerOcclusion(tree, 256, 1)) << "deterministic";
}

}  // namespace
}  // namespace canopy
