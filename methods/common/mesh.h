#pragma once

#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "common/gl/device.h"
#include "common/tree.h"
#include "methods/common/lod_instances.h"
#include "methods/common/wood_levels.h"
#include "methods/method.h"

namespace canopy {

// The interleaved vertex of every textured mesh: position, normal, uv (mesh.vert locations 0–2;
// instance matrices at 4–7).
struct MeshVertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;
};

gl::VertexArray makeMeshVertexArray(const gl::Buffer& vertices, const gl::Buffer& indices);

// Uniforms every shading-aware program takes: view-projection, lit flag, light, ambient.
void setFrameUniforms(const gl::Program& program, const FrameContext& frame);

// The wood parameters every impostor shares; the reference (polygonal) always draws the full mesh.
// The help of every method's `wood_first` parameter (the reference's too).
inline constexpr const char* kWoodFirstHelp =
    "draw the opaque wood before the leaves, so the depth test rejects the leaf fragments it "
    "hides before their shaders run (false: after the leaves; the same image either way)";

struct WoodParams {
  bool draw = true;
  float errorPixels = 0.1f;
  bool first = false;

  template <class Visitor>
  void visit(Visitor& v) {
    v("wood", draw, "draw the trunk and branches as geometry");
    v("wood_error_px", errorPixels, 0.0f, 100.0f,
      "wood levels of detail: the largest deviation of the simplified trunk and branches, in "
      "output pixels (0: the full mesh always)");
    v("wood_first", first, kWoodFirstHelp);
  }
  bool levels() const { return draw && errorPixels > 0.0f; }  // whether the bake simplifies
};

// The trunk and branches, drawn the same way by the reference and every impostor (the papers
// replace foliage only): triangles grouped by material, base colour × optional texture. With
// levels (bake's `levels`), each instance draws the coarsest simplified mesh whose error spans at
// most the draw's `errorPixels` output pixels at the instance's distance, so far trees cost a few
// hundred triangles and branches thinner than that vanish.
class WoodRenderer {
 public:
  // `captured`: per image set (decreasing belowPixels), the wood triangles the method's images
  // hold for trees whose projected radius is below its belowPixels; such trees draw only the
  // rest (one WoodLevels residual chain each). Empty: every tree draws the full chain.
  void bake(const Tree& tree, bool levels, const std::vector<CapturedWood>& captured = {});
  void upload(gl::Device& device, bool mipmaps);
  // Draws `instances` (also in frame.instanceBuffer, in span order).
  void draw(const FrameContext& frame, std::span<const Instance> instances,
            float errorPixels = 0.0f);
  // Runs `drawLeaves` and draws the wood as `params` says: before the leaves with
  // params.first, after them otherwise, not at all without params.draw.
  void drawAround(const WoodParams& params, const FrameContext& frame,
                  std::span<const Instance> instances, const std::function<void()>& drawLeaves);
  void save(AssetFolder& asset) const;  // blobs and images prefixed "wood_", header key "wood"
  void load(AssetFolder& asset);
  size_t triangleCount() const { return mLevels.levels() == 0 ? 0 : mLevels.triangles(0); }
  // The levels for bake reports: triangles and error bound (world units) of each.
  nlohmann::json describeLevels() const;
  // `report` with "wood_levels" (describeLevels) and "wood_back_faces_culled" (WoodMesh::solid)
  // added: every method's bake report has them.
  nlohmann::json withLevels(nlohmann::json report) const;
  // Like Method::lodSignature / instancesPerLevel for the last draw's wood (empty without levels).
  uint64_t lodSignature() const { return mLodUsed ? mLod.signature() : 0; }
  std::vector<uint64_t> instancesPerLevel() const;

 private:
  // Level `level`'s ranges for `count` instances from `first` in `instanceBuffer`.
  void drawLevel(size_t level, GLuint instanceBuffer, GLint first, GLsizei count) const;

  std::vector<MeshVertex> mVertices;
  WoodLevels mLevels;
  Aabb mBounds;         // the tree's: the LoD radius, as the leaves' LoD measures it
  bool mSolid = false;  // WoodMesh::solid: back faces culled
  std::vector<WoodMaterial> mMaterials;
  std::vector<ImageRgba8> mTextures;
  gl::Buffer mVbo, mIbo;
  gl::VertexArray mVao;
  std::vector<gl::Texture> mGpuTextures;
  gl::Program mProgram;
  LodInstances mLod;
  bool mLodUsed = false;  // the last draw sorted instances into levels
};

}  // namespace canopy
