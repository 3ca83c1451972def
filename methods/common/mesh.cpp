#include "methods/common/mesh.h"

#include <algorithm>
#include <array>
#include <numeric>

#include <glm/geometric.hpp>

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

namespace {

// The wood's triangles as indices sorted by material, so each material is one range.
void sortByMaterial(const WoodMesh& wood, std::vector<uint32_t>& indices,
                    std::vector<WoodRange>& ranges) {
  std::vector<uint32_t> order(wood.triangleCount());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return wood.materialIds[a] < wood.materialIds[b];
  });
  indices.clear();
  ranges.clear();
  for (uint32_t t : order) {
    const uint32_t material = wood.materialIds[t];
    if (ranges.empty() || ranges.back().material != material) {
      ranges.push_back({static_cast<uint32_t>(indices.size()), 0, material});
    }
    for (int k = 0; k < 3; ++k) indices.push_back(wood.indices[t * 3 + k]);
    ranges.back().count += 3;
  }
}

}  // namespace

void WoodRenderer::bake(const Tree& tree, bool levels, const std::vector<CapturedWood>& captured) {
  const WoodMesh& wood = tree.wood;
  mVertices.clear();
  for (size_t i = 0; i < wood.positions.size(); ++i)
    mVertices.push_back({wood.positions[i], wood.normals[i], wood.uvs[i]});
  mBounds = tree.bounds;
  mSolid = wood.solid;
  // Error bounds from a thousandth of the tree's radius (sub-pixel at the closest views) to a
  // quarter of it (trees a few pixels tall).
  const float radius = 0.5f * glm::length(mBounds.extent());
  const float finest = levels ? 1e-3f * radius : 0.0f, coarsest = 0.25f * radius;
  std::vector<uint32_t> indices;
  std::vector<WoodRange> ranges;
  sortByMaterial(wood, indices, ranges);
  mLevels = buildWoodLevels(wood.positions, indices, ranges, finest, coarsest);
  // Every residual chain filters the full chain alone, so all are built before any is appended.
  std::vector<WoodLevels> residuals;
  for (const CapturedWood& images : captured) {
    // A vertex is in the images when every triangle around it is.
    std::vector<bool> capturedVertices(wood.positions.size(), true);
    for (size_t t = 0; t < wood.triangleCount(); ++t) {
      if (images.triangles[t]) continue;
      for (int k = 0; k < 3; ++k) capturedVertices[wood.indices[t * 3 + k]] = false;
    }
    residuals.push_back(residualLevels(mLevels, capturedVertices));
  }
  for (size_t i = 0; i < residuals.size(); ++i)
    appendResidualLevels(mLevels, residuals[i], captured[i].belowPixels);
  mMaterials = tree.woodMaterials;
  mTextures = tree.woodTextures;
}

void WoodRenderer::upload(gl::Device& device, bool mipmaps) {
  using gl::MemoryCategory;
  mVbo =
      device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices, "wood vertices");
  mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mLevels.indices,
                             mLevels.levels() > 1 ? "wood indices, every level" : "wood indices");
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
  mLod.attach(device, device.owner() + "/wood frame");
}

void WoodRenderer::drawLevel(size_t level, GLuint instanceBuffer, GLint first,
                             GLsizei count) const {
  const gl::Api& g = gl::api();
  bindInstanceMatrices(instanceBuffer, 4, first);
  const size_t begin = mLevels.firstRange(level);
  for (size_t r = begin; r < begin + mLevels.rangesPerLevel[level]; ++r) {
    const WoodRange& range = mLevels.ranges[r];
    const WoodMaterial& material = mMaterials[range.material];
    mProgram.set("uBaseColor",
                 glm::vec3(srgbToLinear(material.baseColor.r), srgbToLinear(material.baseColor.g),
                           srgbToLinear(material.baseColor.b)));
    mProgram.set("uHasTexture", material.texture >= 0 ? 1 : 0);
    if (material.texture >= 0) g.BindTexture(GL_TEXTURE_2D, mGpuTextures[material.texture].id());
    g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                            reinterpret_cast<const void*>(sizeof(uint32_t) * range.first), count);
  }
}

void WoodRenderer::drawAround(const WoodParams& params, const FrameContext& frame,
                              std::span<const Instance> instances,
                              const std::function<void()>& drawLeaves) {
  if (params.draw && params.first) draw(frame, instances, params.errorPixels);
  drawLeaves();
  if (params.draw && !params.first) draw(frame, instances, params.errorPixels);
}

void WoodRenderer::draw(const FrameContext& frame, std::span<const Instance> instances,
                        float errorPixels) {
  mLodUsed = false;
  if (instances.empty() || mLevels.ranges.empty()) return;
  const gl::Api& g = gl::api();
  mProgram.use();
  setFrameUniforms(mProgram, frame);
  mProgram.set("uWoodTexture", 0);
  g.ActiveTexture(GL_TEXTURE0);
  g.BindVertexArray(mVao.id());
  // Solid wood: back faces are hidden behind front faces, so culling them changes no pixel the
  // reference would not change alike, and spares their rasterization (a quarter of the classic
  // cloud's frame at 1000 trees on llvmpipe). A residual level is culled too, though it is open
  // (the captured triangles cut out) and the back faces seen through its gaps would stand in for
  // the captured front faces: drawing them cost the classic cloud 19 % at 1,000 trees on the
  // Table 2 protocol for 0.004 dB on its views (a 400-leaf tree's middle cloud: 0.4 dB).
  if (mSolid) {
    g.Enable(GL_CULL_FACE);
    g.CullFace(GL_BACK);
  }
  const std::vector<float> thresholds =
      mLevels.thresholds(0.5f * glm::length(mBounds.extent()), errorPixels);
  // (With a residual chain the thresholds are never empty: small trees draw the residual.)
  if (thresholds.empty()) {
    drawLevel(0, frame.instanceBuffer, 0, static_cast<GLsizei>(instances.size()));
  } else {
    // One instanced draw per level and material: the instances sorted by level in one buffer.
    // A forced level (the viewer's) names the method's level, not the wood's: with a residual
    // chain the wood follows the projected size, so it matches what the images hold.
    FrameContext woodFrame = frame;
    if (mLevels.hasResidual()) woodFrame.forcedLevel = -1;
    mLod.update(woodFrame, instances, mBounds, thresholds);
    mLodUsed = true;
    const std::vector<LodInstances::Range>& levels = mLod.ranges();
    for (size_t level = 0; level < levels.size(); ++level) {
      if (levels[level].count > 0)
        drawLevel(level, mLod.buffer(), levels[level].first, levels[level].count);
    }
  }
  g.BindVertexArray(0);
  g.Disable(GL_CULL_FACE);  // the harness's state for every other draw
}

std::vector<uint64_t> WoodRenderer::instancesPerLevel() const {
  std::vector<uint64_t> counts;
  if (!mLodUsed) return counts;
  for (const LodInstances::Range& range : mLod.ranges()) counts.push_back(uint64_t(range.count));
  return counts;
}

nlohmann::json WoodRenderer::describeLevels() const {
  nlohmann::json levels = nlohmann::json::array();
  for (size_t level = 0; level < mLevels.levels(); ++level)
    levels.push_back({{"triangles", mLevels.triangles(level)},
                      {"error", mLevels.errors[level]},
                      {"residual", mLevels.isResidual(level)}});
  return levels;
}

nlohmann::json WoodRenderer::withLevels(nlohmann::json report) const {
  report["wood_levels"] = describeLevels();
  report["wood_back_faces_culled"] = mSolid;
  return report;
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

// One level of detail: how many of wood_ranges.bin it takes and its error bound.
struct WoodLevelFields {
  uint32_t ranges = 0;
  float error = 0.0f;
  template <class V>
  void visit(V& v) {
    v("ranges", ranges);
    v("error", error);
  }
};

struct WoodFields {
  struct Wood {
    std::vector<WoodMaterialFields> materials;
    size_t textures = 0;
    std::vector<WoodLevelFields> levels;
    std::vector<ResidualChain> residualChains;  // WoodLevels::residualChains
    std::array<float, 3> boundsMin{}, boundsMax{};
    bool solid = false;
    template <class V>
    void visit(V& v) {
      v("materials", materials);
      v("solid", solid);
      v("textures", textures);
      v("levels", levels);
      v("residual_chains", residualChains);
      v("bounds_min", boundsMin);
      v("bounds_max", boundsMax);
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
  asset.writeBlob("wood_indices.bin", mLevels.indices);
  asset.writeBlob("wood_ranges.bin", mLevels.ranges);
  WoodFields fields;
  for (size_t level = 0; level < mLevels.levels(); ++level) {
    fields.wood.levels.push_back({mLevels.rangesPerLevel[level], mLevels.errors[level]});
  }
  fields.wood.residualChains = mLevels.residualChains;
  fields.wood.boundsMin = {mBounds.min.x, mBounds.min.y, mBounds.min.z};
  fields.wood.boundsMax = {mBounds.max.x, mBounds.max.y, mBounds.max.z};
  for (const WoodMaterial& m : mMaterials) {
    fields.wood.materials.push_back(
        {m.name, {m.baseColor.r, m.baseColor.g, m.baseColor.b, m.baseColor.a}, m.texture});
  }
  fields.wood.textures = mTextures.size();
  fields.wood.solid = mSolid;
  asset.writeImages("wood_{}.png", mTextures);
  asset.writeFields(fields);
}

void WoodRenderer::load(AssetFolder& asset) {
  const std::string folder = asset.folder().string();
  mVertices = asset.readBlobAs<MeshVertex>("wood_vertices.bin");
  mLevels = {};
  mLevels.indices = asset.readBlobAs<uint32_t>("wood_indices.bin");
  mLevels.ranges = asset.readBlobAs<WoodRange>("wood_ranges.bin");
  WoodFields fields;
  asset.readFields(fields);
  for (const WoodLevelFields& level : fields.wood.levels) {
    mLevels.rangesPerLevel.push_back(level.ranges);
    mLevels.errors.push_back(level.error);
  }
  mLevels.residualChains = fields.wood.residualChains;
  const auto& lo = fields.wood.boundsMin;
  const auto& hi = fields.wood.boundsMax;
  mBounds = {glm::vec3(lo[0], lo[1], lo[2]), glm::vec3(hi[0], hi[1], hi[2])};
  mSolid = fields.wood.solid;
  if (mLevels.levels() == 0 || !mLevels.consistent() || mBounds.empty())
    throwInputError("{}: corrupt wood levels", folder);
  mMaterials.clear();
  for (const WoodMaterialFields& m : fields.wood.materials) {
    const auto& c = m.baseColor;
    mMaterials.push_back({m.name, glm::vec4(c[0], c[1], c[2], c[3]), m.texture});
  }
  mTextures = asset.readImages("wood_{}.png", fields.wood.textures);
  for (const WoodRange& r : mLevels.ranges) {
    if (r.material >= mMaterials.size()) throwInputError("{}: corrupt wood ranges", folder);
  }
  for (uint32_t i : mLevels.indices) {
    if (i >= mVertices.size()) throwInputError("{}: corrupt wood indices", folder);
  }
  for (const WoodMaterial& m : mMaterials) {
    if (m.texture >= static_cast<int>(mTextures.size()))
      throwInputError("{}: corrupt wood material", folder);
  }
}

}  // namespace canopy
