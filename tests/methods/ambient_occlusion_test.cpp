#include "methods/common/ambient_occlusion.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace canopy {
namespace {

TEST(AmbientOcclusionFit, ReproducesAPlanarFieldExactly) {
  // Values from an affine field f(p) = 0.3 + 0.8·x − 0.5·y at the corners of a tilted leaf's
  // projection (a general quadrilateral inside the sprite square).
  const auto field = [](glm::vec2 p) { return 0.3f + 0.8f * p.x - 0.5f * p.y; };
  const std::vector<glm::vec2> points = {
      {-0.31f, -0.12f}, {0.22f, -0.28f}, {0.35f, 0.19f}, {-0.18f, 0.33f}, {0.02f, 0.05f}};
  std::vector<float> values;
  for (const glm::vec2& p : points) values.push_back(field(p));
  const glm::vec2 centre(0.01f, 0.02f);
  const float side = 0.8f;
  const glm::vec4 corners = fitCornerValues(points, values, centre, side);
  // Bilinear interpolation of the fitted corners reproduces the field everywhere in the sprite.
  for (float s : {0.0f, 0.25f, 0.5f, 0.9f, 1.0f}) {
    for (float t : {0.0f, 0.3f, 0.75f, 1.0f}) {
      const glm::vec2 p = centre + (glm::vec2(s, t) - 0.5f) * side;
      EXPECT_NEAR(interpolateCorners(corners, {s, t}), field(p), 1e-5f);
    }
  }
  // Collinear points cannot determine the corners: the fit still reproduces them.
  const std::vector<glm::vec2> line = {{-0.2f, 0.0f}, {0.0f, 0.0f}, {0.2f, 0.0f}};
  std::vector<float> lineValues;
  for (const glm::vec2& p : line) lineValues.push_back(field(p));
  const glm::vec4 lineCorners = fitCornerValues(line, lineValues, {0, 0}, 1.0f);
  for (const glm::vec2& p : line)
    EXPECT_NEAR(interpolateCorners(lineCorners, p + 0.5f), field(p), 1e-5f);
}

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
