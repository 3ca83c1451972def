#include "common/lsystem.h"

#include <gtest/gtest.h>

#include <cstring>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "test_support.h"

namespace canopy {
namespace {

// Serialises every field that defines a tree, so "byte-identical" can be checked exactly.
std::string serialize(const Tree& tree) {
  std::string bytes;
  auto append = [&](const void* data, size_t size) {
    bytes.append(static_cast<const char*>(data), size);
  };
  append(tree.wood.positions.data(), tree.wood.positions.size() * sizeof(glm::vec3));
  append(tree.wood.normals.data(), tree.wood.normals.size() * sizeof(glm::vec3));
  append(tree.wood.indices.data(), tree.wood.indices.size() * sizeof(uint32_t));
  append(tree.leaves.data(), tree.leaves.size() * sizeof(Leaf));
  for (const LeafTexture& t : tree.leafTextures) {
    append(t.front.pixels.data(), t.front.pixels.size());
    append(t.back.pixels.data(), t.back.pixels.size());
    append(t.normalMap.pixels.data(), t.normalMap.pixels.size());
  }
  for (const BranchNode& n : tree.branches) {
    append(&n.parent, sizeof n.parent);
    append(&n.bounds, sizeof n.bounds);
    append(&n.leafBegin, sizeof n.leafBegin);
    append(&n.subtreeLeafEnd, sizeof n.subtreeLeafEnd);
  }
  return bytes;
}

TEST(LSystem, SamePresetAndSeedGiveByteIdenticalTrees) {
  const Tree a = generateTree(treePreset("shrub"), 3);
  const Tree b = generateTree(treePreset("shrub"), 3);
  EXPECT_EQ(serialize(a), serialize(b));
}

TEST(LSystem, DifferentSeedsGiveDifferentTrees) {
  EXPECT_NE(serialize(generateTree(treePreset("sparse"), 1)),
            serialize(generateTree(treePreset("sparse"), 2)));
}

TEST(LSystem, PresetsHaveTheirLeafCounts) {
  EXPECT_EQ(generateTree(treePreset("broadleaf"), 1).leaves.size(), 20000u);
  EXPECT_EQ(generateTree(treePreset("shrub"), 1).leaves.size(), 2500u);
  EXPECT_EQ(generateTree(treePreset("sparse"), 1).leaves.size(), 1000u);
  LSystemTreeParams scaled = treePreset("sparse");
  scaled.leaves = 12345;
  EXPECT_EQ(generateTree(scaled, 1).leaves.size(), 12345u);
}

// WoodMesh::solid lets every drawing cull the wood's back faces; that is only right if each
// triangle is wound counter-clockwise seen from outside, i.e. along its outward vertex normals.
TEST(LSystem, WoodIsSolidAndWoundOutward) {
  for (const std::string& preset : treePresetNames()) {
    const Tree tree = generateTree(treePreset(preset), 2);
    EXPECT_TRUE(tree.wood.solid) << preset;
    const WoodMesh& wood = tree.wood;
    size_t inward = 0;
    for (size_t t = 0; t < wood.triangleCount(); ++t) {
      const uint32_t* corner = &wood.indices[3 * t];
      const glm::vec3 winding = glm::cross(wood.positions[corner[1]] - wood.positions[corner[0]],
                                           wood.positions[corner[2]] - wood.positions[corner[0]]);
      const glm::vec3 outward =
          wood.normals[corner[0]] + wood.normals[corner[1]] + wood.normals[corner[2]];
      if (glm::dot(winding, outward) <= 0.0f) ++inward;
    }
    EXPECT_EQ(inward, 0u) << preset << ": of " << wood.triangleCount() << " triangles";
  }
}

TEST(LSystem, UnknownPresetIsAnInputError) {
  EXPECT_THROW(treePreset("palm"), InputError);
}

class HierarchyInvariants : public testing::TestWithParam<std::string> {};

TEST_P(HierarchyInvariants, EveryBoxContainsItsChildrenAndItsLeaves) {
  const Tree tree = generateTree(treePreset(GetParam()), 5);
  ASSERT_FALSE(tree.branches.empty());
  const float epsilon = 1e-5f * tree.boundingSphereRadius();
  EXPECT_EQ(tree.branches[0].parent, -1);
  EXPECT_EQ(tree.branches[0].leafBegin, 0u);
  EXPECT_EQ(tree.branches[0].subtreeLeafEnd, tree.leaves.size());
  for (size_t n = 0; n < tree.branches.size(); ++n) {
    const BranchNode& node = tree.branches[n];
    for (int32_t child : node.children) {
      ASSERT_GT(child, static_cast<int32_t>(n)) << "nodes are in pre-order";
      EXPECT_EQ(tree.branches[child].parent, static_cast<int32_t>(n));
      EXPECT_EQ(tree.branches[child].level, node.level + 1);
      EXPECT_TRUE(node.bounds.contains(tree.branches[child].bounds, epsilon))
          << "node " << n << " child " << child;
      EXPECT_GE(tree.branches[child].leafBegin, node.leafEnd);
      EXPECT_LE(tree.branches[child].subtreeLeafEnd, node.subtreeLeafEnd);
    }
    for (uint32_t l = node.leafBegin; l < node.subtreeLeafEnd; ++l) {
      for (int c = 0; c < 4; ++c)
        EXPECT_TRUE(node.bounds.contains(tree.leaves[l].corner(c), epsilon));
    }
    for (uint32_t l = node.leafBegin; l < node.leafEnd; ++l)
      EXPECT_EQ(tree.leaves[l].branch, static_cast<int32_t>(n));
  }
  // Every leaf belongs to exactly one node's own range: the own ranges tile [0, leaves).
  size_t covered = 0;
  for (const BranchNode& node : tree.branches) covered += node.leafEnd - node.leafBegin;
  EXPECT_EQ(covered, tree.leaves.size());
  // The root box is the tree's box.
  EXPECT_TRUE(tree.branches[0].bounds.contains(tree.bounds, epsilon));
  EXPECT_TRUE(tree.bounds.contains(tree.branches[0].bounds, epsilon));
}

INSTANTIATE_TEST_SUITE_P(Presets, HierarchyInvariants,
                         testing::Values("broadleaf", "shrub", "sparse"));

TEST(LSystem, PushAndPopCreateOneBoxPerBracketPair) {
  // "F [ F L ] [ F [ F L ] ]": three brackets, so root + 3 boxes, nested as written.
  std::vector<Module> modules;
  const auto m = [](char s, float a = 0, float b = 0, float c = 0, float d = 0) {
    return Module::make(s, a, b, c, d);
  };
  modules = {m('F', 1, 0.1f),
             m('['),
             m('&', 45),
             m('F', 1, 0.05f),
             m('L', 1, 40, 0, 0),
             m(']'),
             m('['),
             m('&', -45),
             m('F', 1, 0.05f),
             m('['),
             m('F', 0.5f, 0.02f),
             m('L', 1, 40, 0, 0),
             m(']'),
             m(']')};
  LSystemTreeParams params = treePreset("sparse");
  Tree tree = interpretTreeString(modules, params, 1);
  ASSERT_EQ(tree.branches.size(), 4u);
  EXPECT_EQ(tree.branches[1].parent, 0);
  EXPECT_EQ(tree.branches[2].parent, 0);
  EXPECT_EQ(tree.branches[3].parent, 2);
  EXPECT_EQ(tree.branches[3].level, 2);
  ASSERT_EQ(tree.leaves.size(), 2u);
  EXPECT_EQ(tree.leaves[0].branch, 1);
  EXPECT_EQ(tree.leaves[1].branch, 3);
  std::vector<Module> unbalanced = {m('['), m('F', 1, 0.1f)};
  EXPECT_THROW(interpretTreeString(unbalanced, params, 1), InputError);
}

TEST(LeafTexture, HasOpaqueBladeTransparentCornersAndADistinctBack) {
  const Tree tree = test::smallTree(50);
  const LeafTexture& t = tree.leafTextures[0];
  const int s = t.front.width;
  EXPECT_EQ(t.front.at(s / 2, s / 2)[3], 255);  // blade centre
  EXPECT_EQ(t.front.at(0, 0)[3], 0);            // corners are outside the outline
  EXPECT_EQ(t.front.at(s - 1, s - 1)[3], 0);
  EXPECT_NE(t.front.pixels, t.back.pixels);
  EXPECT_EQ(t.normalMap.width, s);
}

}  // namespace
}  // namespace canopy
