#include "methods/polygonal/polygonal.h"

#include <algorithm>
#include <numeric>

#include "common/config.h"
#include "common/image.h"
#include "methods/common/ambient_occlusion.h"
#include "methods/common/mesh.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct PolygonalParams {
  bool drawWood = true;
  bool woodFirst = false;
  bool mipmaps = true;
  bool ambientOcclusion = true;
  int aoRays = 32;

  template <class Visitor>
  void visit(Visitor& v) {
    v("wood", drawWood, "draw the trunk and branches (false: leaves only)");
    v("wood_first", woodFirst, kWoodFirstHelp);
    v("mipmaps", mipmaps, "mipmapped leaf textures (trilinear), as a real engine draws them");
    v("ambient_occlusion", ambientOcclusion,
      "lit runs: the leaves' ambient term scaled by the Embree AO the impostors bake "
      "(methods/common/ambient_occlusion), so AO is not counted as error");
    v("ao_rays", aoRays, 1, 4096, "rays per leaf corner (multilayer_indirect's default)");
  }
};

// Leaves of one leaf texture: a contiguous index range.
struct LeafRange {
  uint32_t first = 0;
  uint32_t count = 0;
  uint32_t texture = 0;
};

// The asset header's own part.
struct AssetFields {
  size_t leafTextures = 0;
  template <class V>
  void visit(V& v) {
    v("leaf_textures", leafTextures);
  }
};

class Polygonal final : public Method {
 public:
  explicit Polygonal(PolygonalParams params) : mParams(params) {}

  void bake(const Tree& tree, BakeContext& ctx) override {
    mWood.bake(tree, false);  // the reference keeps the full mesh
    mVertices.clear();
    mIndices.clear();
    mRanges.clear();
    mOcclusion.clear();
    std::vector<glm::vec4> corners;
    if (mParams.ambientOcclusion && ctx.ambientOcclusion && ctx.shading == Shading::kLit)
      corners = computeLeafCornerOcclusion(tree, mParams.aoRays, ctx.seed);
    // Four vertices per leaf, leaves grouped by texture.
    std::vector<uint32_t> order(tree.leaves.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return tree.leaves[a].texture < tree.leaves[b].texture;
    });
    for (uint32_t index : order) {
      const Leaf& leaf = tree.leaves[index];
      if (mRanges.empty() || mRanges.back().texture != leaf.texture) {
        mRanges.push_back({static_cast<uint32_t>(mIndices.size()), 0, leaf.texture});
      }
      const auto base = static_cast<uint32_t>(mVertices.size());
      for (int c = 0; c < 4; ++c) {
        mVertices.push_back({leaf.corner(c), leaf.normal, leaf.cornerUv(c)});
        if (!corners.empty()) mOcclusion.push_back(corners[index][c]);
      }
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
      mRanges.back().count += 6;
    }
    mLeafImages.clear();
    for (const LeafTexture& texture : tree.leafTextures)
      mLeafImages.emplace_back(texture.front, texture.back);
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mVbo =
        device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices, "leaf vertices");
    mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mIndices,
                               "leaf indices");
    mVao = makeMeshVertexArray(mVbo, mIbo);
    if (!mOcclusion.empty()) {
      mOcclusionVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mOcclusion,
                                          "leaf corner ambient occlusion");
      const gl::Api& g = gl::api();
      g.BindVertexArray(mVao.id());
      g.BindBuffer(GL_ARRAY_BUFFER, mOcclusionVbo.id());
      g.EnableVertexAttribArray(3);
      g.VertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
      g.BindVertexArray(0);
      g.BindBuffer(GL_ARRAY_BUFFER, 0);
    }
    mTextures.clear();
    for (const auto& [front, back] : mLeafImages) {
      // One layer when the underside is the same image (most files), two otherwise.
      const bool twoSided =
          back.pixels != front.pixels && back.width == front.width && back.height == front.height;
      gl::Texture texture = device.createTexture(
          {GL_TEXTURE_2D_ARRAY, front.width, front.height, twoSided ? 2 : 1, GL_SRGB8_ALPHA8,
           mParams.mipmaps, MemoryCategory::kTexture, "leaf images"});
      device.uploadTextureLayer(texture, 0, GL_RGBA, GL_UNSIGNED_BYTE, front.pixels.data());
      if (twoSided)
        device.uploadTextureLayer(texture, 1, GL_RGBA, GL_UNSIGNED_BYTE, back.pixels.data());
      if (texture.levels > 1) device.generateMipmaps(texture);
      gl::setTextureSampling(texture, true, false);
      mTextures.push_back(std::move(texture));
    }
    mProgram = device.createProgram({gl::embeddedShader("methods/common/mesh.vert"),
                                     gl::embeddedShader("methods/polygonal/polygonal_leaf.frag")});
    if (mParams.drawWood) mWood.upload(device, mParams.mipmaps);
  }

  // The reference's wood: always the full mesh.
  WoodParams woodParams() const {
    return {.draw = mParams.drawWood, .errorPixels = 0.0f, .first = mParams.woodFirst};
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    mWood.drawAround(woodParams(), frame, instances, [&] { drawLeaves(frame, instances); });
  }

  // Everything but the wood (drawAround orders the two).
  void drawLeaves(const FrameContext& frame, std::span<const Instance> instances) {
    const gl::Api& g = gl::api();
    const auto count = static_cast<GLsizei>(instances.size());
    mProgram.use();
    setFrameUniforms(mProgram, frame);
    mProgram.set("uLeafImages", 0);
    mProgram.set("uHasVertexOcclusion", mOcclusion.empty() ? 0 : 1);
    g.BindVertexArray(mVao.id());
    bindInstanceMatrices(frame.instanceBuffer, 4);
    g.ActiveTexture(GL_TEXTURE0);
    for (const LeafRange& range : mRanges) {
      const gl::Texture& texture = mTextures[range.texture];
      mProgram.set("uBackLayer", float(texture.desc.layers - 1));
      g.BindTexture(GL_TEXTURE_2D_ARRAY, texture.id());
      g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                              reinterpret_cast<const void*>(sizeof(uint32_t) * range.first), count);
    }
    g.BindVertexArray(0);
    mLeafPolygonsDrawn = uint64_t(mIndices.size() / 6) * instances.size();
  }

  uint64_t leafPolygonsDrawn() const override { return mLeafPolygonsDrawn; }
  // Its wood, as every impostor reports it: how it is drawn is part of the ground truth.
  nlohmann::json bakeReport() const override { return mWood.withLevels(nlohmann::json::object()); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }

  void save(AssetFolder& asset) const override {
    asset.describe("polygonal", effectiveParams(), nlohmann::json::object());
    asset.writeBlob("leaf_vertices.bin", mVertices);
    asset.writeBlob("leaf_indices.bin", mIndices);
    asset.writeBlob("leaf_ranges.bin", mRanges);
    asset.writeBlob("leaf_occlusion.bin", mOcclusion);
    std::vector<ImageRgba8> fronts, backs;
    for (const auto& [front, back] : mLeafImages) fronts.push_back(front), backs.push_back(back);
    asset.writeImages("leaf_{}_front.png", fronts);
    asset.writeImages("leaf_{}_back.png", backs);
    asset.writeFields(AssetFields{mLeafImages.size()});
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    asset.readHeaderOf("polygonal");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    mVertices = asset.readBlobAs<MeshVertex>("leaf_vertices.bin");
    mIndices = asset.readBlobAs<uint32_t>("leaf_indices.bin");
    mRanges = asset.readBlobAs<LeafRange>("leaf_ranges.bin");
    mOcclusion = asset.readBlobAs<float>("leaf_occlusion.bin");
    if (!mOcclusion.empty() && mOcclusion.size() != mVertices.size())
      throwInputError("{}: leaf occlusion does not match the leaf vertices", folder);
    const auto fronts = asset.readImages("leaf_{}_front.png", fields.leafTextures);
    const auto backs = asset.readImages("leaf_{}_back.png", fields.leafTextures);
    mLeafImages.clear();
    for (size_t i = 0; i < fronts.size(); ++i) mLeafImages.emplace_back(fronts[i], backs[i]);
    for (const LeafRange& r : mRanges) {
      if (size_t(r.first) + r.count > mIndices.size() || r.texture >= mLeafImages.size()) {
        throwInputError("{}: corrupt leaf ranges", folder);
      }
    }
    for (uint32_t i : mIndices) {
      if (i >= mVertices.size()) throwInputError("{}: corrupt leaf indices", folder);
    }
    mWood.load(asset);
    asset.finishReading();
  }

 private:
  PolygonalParams mParams;
  WoodRenderer mWood;
  std::vector<MeshVertex> mVertices;
  std::vector<uint32_t> mIndices;
  std::vector<LeafRange> mRanges;
  std::vector<float> mOcclusion;  // per leaf vertex (lit runs with AO), else empty
  std::vector<std::pair<ImageRgba8, ImageRgba8>> mLeafImages;  // front, back
  uint64_t mLeafPolygonsDrawn = 0;
  gl::Buffer mVbo, mIbo, mOcclusionVbo;
  gl::VertexArray mVao;
  std::vector<gl::Texture> mTextures;
  gl::Program mProgram;
};

}  // namespace

void registerPolygonal(MethodRegistry& registry) {
  addMethod<Polygonal, PolygonalParams>(
      registry, "polygonal", "the reference: wood mesh and every leaf quad with alpha test",
      {.cost = {.bakeSeconds = 0.0, .frameCost = 1.0}});
}

}  // namespace canopy
