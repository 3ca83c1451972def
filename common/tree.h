#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "common/image.h"

namespace canopy {

// Axis-aligned box; a default-constructed box is empty and grows with extend().
struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::max()};
  glm::vec3 max{std::numeric_limits<float>::lowest()};

  bool empty() const { return min.x > max.x; }
  void extend(const glm::vec3& point);
  void extend(const Aabb& box);
  bool contains(const glm::vec3& point, float epsilon = 0.0f) const;
  bool contains(const Aabb& box, float epsilon = 0.0f) const;
  glm::vec3 center() const { return (min + max) * 0.5f; }
  glm::vec3 extent() const { return max - min; }
  float volume() const;
};

// The trunk and branches: an indexed triangle mesh.
struct WoodMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;     // unit, one per position
  std::vector<glm::vec2> uvs;         // one per position
  std::vector<uint32_t> indices;      // three per triangle
  std::vector<uint16_t> materialIds;  // one per triangle, into Tree::woodMaterials
  // The wood stands for opaque branches whose triangles are wound counter-clockwise seen from
  // outside, so every drawing (the reference's too) culls back faces: they show only through a
  // tube's open end, where a real branch is solid. Set by a source that builds the wood that way
  // (the L-system); a loaded file makes no such promise (its normals may be derived from the
  // winding, so they cannot vouch for it) and is drawn double-sided.
  bool solid = false;

  size_t triangleCount() const { return indices.size() / 3; }
  // The connected parts (a branch segment's tube for the built-in trees): one part number per
  // vertex, vertices of one triangle or at one position in one part (files split vertices along
  // seams, so positions, not indices, say what touches), numbered in the order of each part's
  // first vertex.
  std::vector<uint32_t> vertexParts() const;
};

struct WoodMaterial {
  std::string name;
  glm::vec4 baseColor{1.0f};  // sRGB-encoded RGBA, multiplies the texture
  int texture = -1;           // index into Tree::woodTextures, -1 for none
};

// The images of one kind of leaf. All images are sRGB RGBA with straight alpha; the leaf blade
// is where alpha >= 0.5 (the alpha-test threshold every method uses).
struct LeafTexture {
  std::string name;
  ImageRgba8 front;
  ImageRgba8 back;       // the underside; equal to front when the source has only one image
  ImageRgba8 normalMap;  // optional tangent-space normal map (empty when absent)
};

// One leaf: a planar textured quad. Corners are center ± axisU·halfExtents.x ± axisV·halfExtents.y,
// with texture coordinate uvMin at (−,−) and uvMax at (+,+).
struct Leaf {
  glm::vec3 center{0.0f};
  glm::vec3 normal{0.0f, 0.0f, 1.0f};  // unit; the front side faces along it
  glm::vec3 axisU{1.0f, 0.0f, 0.0f};   // unit, in the plane, direction of increasing u
  glm::vec3 axisV{0.0f, 1.0f, 0.0f};   // unit, in the plane, direction of increasing v
  glm::vec2 halfExtents{0.5f};         // along axisU and axisV
  glm::vec2 uvMin{0.0f};
  glm::vec2 uvMax{1.0f};
  uint32_t texture = 0;  // index into Tree::leafTextures
  int32_t branch = -1;   // the BranchNode it hangs on (-1 when the tree has no hierarchy)

  // Corner i in counter-clockwise order seen from the front: (−,−), (+,−), (+,+), (−,+).
  glm::vec3 corner(int i) const;
  glm::vec2 cornerUv(int i) const;
  float area() const { return 4.0f * halfExtents.x * halfExtents.y; }
};

// A node of the branch hierarchy (bounding-box paper §3.1–3.2.1). Nodes are stored in pre-order
// (a parent before its children) and leaves are sorted by node, so a node's own leaves are
// [leafBegin, leafEnd) and its whole subtree's leaves are [leafBegin, subtreeLeafEnd).
struct BranchNode {
  int32_t parent = -1;
  std::vector<int32_t> children;
  int32_t level = 0;  // depth; the root is level 0
  Aabb bounds;        // everything in the subtree: wood and leaves
  uint32_t leafBegin = 0;
  uint32_t leafEnd = 0;
  uint32_t subtreeLeafEnd = 0;
};

struct CaptureSet;

struct Tree {
  std::string name;
  WoodMesh wood;
  std::vector<WoodMaterial> woodMaterials;
  std::vector<ImageRgba8> woodTextures;
  std::vector<Leaf> leaves;
  std::vector<LeafTexture> leafTextures;
  std::vector<BranchNode> branches;  // empty when the source has no hierarchy
  Aabb bounds;
  // Set for a tree known only from photographs (a capture folder): no leaves, no wood, and
  // `bounds` the visual hull of its training views.
  std::shared_ptr<const CaptureSet> captures;

  glm::vec3 boundingSphereCenter() const { return bounds.center(); }
  float boundingSphereRadius() const;
};

// Recomputes bounds, checks invariants the methods rely on (finite data, unit normals, valid
// indices, texture ids), and throws InputError naming `source` when they do not hold.
void finalizeTree(Tree& tree, const std::string& source);

// Sorts leaves by branch node and fills every node's leaf ranges and subtree bounds.
void indexLeavesByBranch(Tree& tree);

}  // namespace canopy
