#pragma once

#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "common/gl/device.h"
#include "common/tree.h"
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

// The trunk and branches, drawn the same way by the reference and every impostor (the papers
// replace foliage only): triangles grouped by material, base colour × optional texture.
class WoodRenderer {
 public:
  void bake(const Tree& tree);
  void upload(gl::Device& device, bool mipmaps);
  // Draws the frame's `instances` instances (frame.instanceBuffer: every method draws the
  // trunk of every tree).
  void draw(const FrameContext& frame, size_t instances) const;
  void save(AssetFolder& asset) const;  // blobs and images prefixed "wood_", header key "wood"
  void load(AssetFolder& asset);
  size_t triangleCount() const { return mIndices.size() / 3; }

 private:
  struct Range {
    uint32_t first = 0;
    uint32_t count = 0;
    uint32_t material = 0;
  };
  std::vector<MeshVertex> mVertices;
  std::vector<uint32_t> mIndices;
  std::vector<Range> mRanges;
  std::vector<WoodMaterial> mMaterials;
  std::vector<ImageRgba8> mTextures;
  gl::Buffer mVbo, mIbo;
  gl::VertexArray mVao;
  std::vector<gl::Texture> mGpuTextures;
  gl::Program mProgram;
};

}  // namespace canopy
