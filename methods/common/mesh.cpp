#include "methods/common/mesh.h"

#include <algorithm>
#include <array>
#include <numeric>

#include <fmt/format.h>

#include "common/image.h"

namespace canopy {

gl::VertexArray makeMeshVertexArray(const gl::Buffer& vertices, const gl::Buffer& indices) {
  const gl::Api& g = gl::api();
  gl::VertexArray vao = gl::createVertexArray();
  g.BindBuffer(GL_ARRAY_BUFFER, vertices.id());
  g.EnableVertexAttribArray(0);
  g.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        reinterpret_cast<const void*>(offsetof(MeshVertex, position)));
  g.EnableVertexAttribArray(1);
  g.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        reinterpret_cast<const void*>(offsetof(MeshVertex, normal)));
  g.EnableVertexAttribArray(2);
  g.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        reinterpret_cast<const void*>(offsetof(MeshVertex, uv)));
  g.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices.id());
  g.BindVertexArray(0);
  g.BindBuffer(GL_ARRAY_BUFFER, 0);
  return vao;
}

void setFrameUniforms(const gl::Program& program, const FrameContext& frame) {
  program.set("uViewProjection", frame.projection * frame.view);
  program.set("uLit", frame.shading == Shading::kLit ? 1 : 0);
  program.set("uLightDirection", frame.lightDirection);
  program.set("uAmbient", frame.ambient);
  program.set("uUseAmbientOcclusion", frame.ambientOcclusion ? 1 : 0);
  program.set("uShadows", frame.shadowMap != 0 && frame.shading == Shading::kLit ? 1 : 0);
  program.set("uShadowMap", kShadowMapUnit);
  program.set("uLightViewProjection", frame.lightViewProjection);
  program.set("uDitherKeep", frame.ditherKeep);
}

void WoodRenderer::bake(const Tree& tree) {
  const WoodMesh& wood = tree.wood;
  mVertices.clear();
  mIndices.clear();
  mRanges.clear();
  for (size_t i = 0; i < wood.positions.size(); ++i)
    mVertices.push_back({wood.positions[i], wood.normals[i], wood.uvs[i]});
  // Triangles sorted by material so each material is one range.
  std::vector<uint32_t> order(wood.triangleCount());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return wood.materialIds[a] < wood.materialIds[b];
  });
  for (uint32_t t : order) {
    const uint32_t material = wood.materialIds[t];
    if (mRanges.empty() || mRanges.back().material != material) {
      mRanges.push_back({static_cast<uint32_t>(mIndices.size()), 0, material});
    }
    for (int k = 0; k < 3; ++k) mIndices.push_back(wood.indices[t * 3 + k]);
    mRanges.back().count += 3;
  }
  mMaterials = tree.woodMaterials;
  mTextures = tree.woodTextures;
}

void WoodRenderer::upload(gl::Device& device, bool mipmaps) {
  using gl::MemoryCategory;
  mVbo =
      device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices, "wood vertices");
  mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mIndices,
                             "wood indices");
  mVao = makeMeshVertexArray(mVbo, mIbo);
  mGpuTextures.clear();
  for (const ImageRgba8& image : mTextures) {
    gl::Texture texture =
        device.createTexture({GL_TEXTURE_2D, image.width, image.height, 1, GL_SRGB8_ALPHA8, mipmaps,
                              MemoryCategory::kTexture, "wood texture"});
    device.uploadTexture(texture, GL_RGBA, GL_UNSIGNED_BYTE, image.pixels.data());
    gl::setTextureSampling(texture, true, true);
    mGpuTextures.push_back(std::move(texture));
  }
  mProgram = device.createProgram({gl::embeddedShader("methods/common/mesh.vert"),
                                   gl::embeddedShader("methods/common/wood.frag")});
}

void WoodRenderer::draw(const FrameContext& frame, size_t instances) const {
  const auto count = static_cast<GLsizei>(instances);
  if (count == 0 || mRanges.empty()) return;
  const gl::Api& g = gl::api();
  mProgram.use();
  setFrameUniforms(mProgram, frame);
  mProgram.set("uWoodTexture", 0);
  g.ActiveTexture(GL_TEXTURE0);
  g.BindVertexArray(mVao.id());
  bindInstanceMatrices(frame.instanceBuffer, 4);
  for (const Range& range : mRanges) {
    const WoodMaterial& material = mMaterials[range.material];
    mProgram.set("uBaseColor",
                 glm::vec3(srgbToLinear(material.baseColor.r), srgbToLinear(material.baseColor.g),
                           srgbToLinear(material.baseColor.b)));
    mProgram.set("uHasTexture", material.texture >= 0 ? 1 : 0);
    if (material.texture >= 0) g.BindTexture(GL_TEXTURE_2D, mGpuTextures[material.texture].id());
    g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                            reinterpret_cast<const void*>(sizeof(uint32_t) * range.first), count);
  }
  g.BindVertexArray(0);
}

namespace {

// The header part "wood": the materials and how many textures the wood_<i>.png files hold.
struct WoodMaterialFields {
  std::string name;
  std::array<float, 4> baseColor{};
  int texture = -1;
  template <class V>
  void visit(V& v) {
    v("name", name);
    v("base_color", baseColor);
    v("texture", texture);
  }
};

struct WoodFields {
  struct Wood {
    std::vector<WoodMaterialFields> materials;
    size_t textures = 0;
    template <class V>
    void visit(V& v) {
      v("materials", materials);
      v("textures", textures);
    }
  } wood;
  template <class V>
  void visit(V& v) {
    v("wood", wood);
  }
};

}  // namespace

void WoodRenderer::save(AssetFolder& asset) const {
  asset.writeBlob("wood_vertices.bin", mVertices);
  asset.writeBlob("wood_indices.bin", mIndices);
  asset.writeBlob("wood_ranges.bin", mRanges);
  WoodFields fields;
  for (const WoodMaterial& m : mMaterials) {
    fields.wood.materials.push_back(
        {m.name, {m.baseColor.r, m.baseColor.g, m.baseColor.b, m.baseColor.a}, m.texture});
  }
  fields.wood.textures = mTextures.size();
  asset.writeImages("wood_{}.png", mTextures);
  asset.writeFields(fields);
}

void WoodRenderer::load(AssetFolder& asset) {
  const std::string folder = asset.folder().string();
  mVertices = asset.readBlobAs<MeshVertex>("wood_vertices.bin");
  mIndices = asset.readBlobAs<uint32_t>("wood_indices.bin");
  mRanges = asset.readBlobAs<Range>("wood_ranges.bin");
  WoodFields fields;
  asset.readFields(fields);
  mMaterials.clear();
  for (const WoodMaterialFields& m : fields.wood.materials) {
    const auto& c = m.baseColor;
    mMaterials.push_back({m.name, glm::vec4(c[0], c[1], c[2], c[3]), m.texture});
  }
  mTextures = asset.readImages("wood_{}.png", fields.wood.textures);
  for (const Range& r : mRanges) {
    if (size_t(r.first) + r.count > mIndices.size() || r.material >= mMaterials.size()) {
      throwInputError("{}: corrupt wood ranges", folder);
    }
  }
  for (uint32_t i : mIndices) {
    if (i >= mVertices.size()) throwInputError("{}: corrupt wood indices", folder);
  }
  for (const WoodMaterial& m : mMaterials) {
    if (m.texture >= static_cast<int>(mTextures.size()))
      throwInputError("{}: corrupt wood material", folder);
  }
}

}  // namespace canopy
