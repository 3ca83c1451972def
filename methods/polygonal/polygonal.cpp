#include "methods/polygonal/polygonal.h"

#include <algorithm>
#include <numeric>

#include <glm/gtc/type_ptr.hpp>

#include "common/config.h"
#include "common/image.h"

namespace canopy {
namespace {

struct PolygonalParams {
  bool drawWood = true;  // draw the trunk and branches (false: leaves only)
  bool mipmaps = true;   // mipmapped leaf textures (trilinear) as a real engine would draw them

  template <class Visitor>
  void visit(Visitor& v) {
    v("wood", drawWood);
    v("mipmaps", mipmaps);
  }
};

// Interleaved vertex: position, normal, uv.
struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;
};

// A contiguous index range drawn with one material or one leaf texture.
struct DrawRange {
  uint32_t first = 0;
  uint32_t count = 0;
  uint32_t material = 0;  // wood material or leaf texture index
};

class Polygonal final : public Method {
 public:
  explicit Polygonal(PolygonalParams params) : mParams(params) {}

  void bake(const Tree& tree, BakeContext&) override {
    mWoodVertices.clear();
    mWoodIndices.clear();
    mWoodRanges.clear();
    mLeafVertices.clear();
    mLeafIndices.clear();
    mLeafRanges.clear();
    // Wood triangles sorted by material so each material is one range.
    const WoodMesh& wood = tree.wood;
    for (size_t i = 0; i < wood.positions.size(); ++i) {
      mWoodVertices.push_back({wood.positions[i], wood.normals[i], wood.uvs[i]});
    }
    std::vector<uint32_t> order(wood.triangleCount());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return wood.materialIds[a] < wood.materialIds[b];
    });
    for (uint32_t t : order) {
      const uint32_t material = wood.materialIds[t];
      if (mWoodRanges.empty() || mWoodRanges.back().material != material) {
        mWoodRanges.push_back({static_cast<uint32_t>(mWoodIndices.size()), 0, material});
      }
      for (int k = 0; k < 3; ++k) mWoodIndices.push_back(wood.indices[t * 3 + k]);
      mWoodRanges.back().count += 3;
    }
    mWoodMaterials = tree.woodMaterials;
    mWoodTextures = tree.woodTextures;
    // Leaves: four vertices each, grouped by leaf texture.
    std::vector<uint32_t> leafOrder(tree.leaves.size());
    std::iota(leafOrder.begin(), leafOrder.end(), 0u);
    std::stable_sort(leafOrder.begin(), leafOrder.end(), [&](uint32_t a, uint32_t b) {
      return tree.leaves[a].texture < tree.leaves[b].texture;
    });
    for (uint32_t index : leafOrder) {
      const Leaf& leaf = tree.leaves[index];
      if (mLeafRanges.empty() || mLeafRanges.back().material != leaf.texture) {
        mLeafRanges.push_back({static_cast<uint32_t>(mLeafIndices.size()), 0, leaf.texture});
      }
      const auto base = static_cast<uint32_t>(mLeafVertices.size());
      for (int c = 0; c < 4; ++c)
        mLeafVertices.push_back({leaf.corner(c), leaf.normal, leaf.cornerUv(c)});
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mLeafIndices.push_back(base + k);
      mLeafRanges.back().count += 6;
    }
    mLeafTextures.clear();
    for (const LeafTexture& texture : tree.leafTextures)
      mLeafTextures.push_back({texture.front, texture.back});
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mWoodVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mWoodVertices,
                                   "wood vertices");
    mWoodIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mWoodIndices,
                                   "wood indices");
    mLeafVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mLeafVertices,
                                   "leaf vertices");
    mLeafIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mLeafIndices,
                                   "leaf indices");
    mWoodVao = makeVertexArray(mWoodVbo, mWoodIbo);
    mLeafVao = makeVertexArray(mLeafVbo, mLeafIbo);
    mLeafGpuTextures.clear();
    for (const auto& [front, back] : mLeafTextures) {
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
      mLeafGpuTextures.push_back(std::move(texture));
    }
    mWoodGpuTextures.clear();
    for (const ImageRgba8& image : mWoodTextures) {
      gl::Texture texture =
          device.createTexture({GL_TEXTURE_2D, image.width, image.height, 1, GL_SRGB8_ALPHA8,
                                mParams.mipmaps, MemoryCategory::kTexture, "wood texture"});
      device.uploadTexture(texture, GL_RGBA, GL_UNSIGNED_BYTE, image.pixels.data());
      gl::setTextureSampling(texture, true, true);
      mWoodGpuTextures.push_back(std::move(texture));
    }
    mLeafProgram =
        device.createProgram({gl::embeddedShader("methods/polygonal/polygonal.vert"),
                              gl::embeddedShader("methods/polygonal/polygonal_leaf.frag")});
    mWoodProgram =
        device.createProgram({gl::embeddedShader("methods/polygonal/polygonal.vert"),
                              gl::embeddedShader("methods/polygonal/polygonal_wood.frag")});
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    const gl::Api& g = gl::api();
    const glm::mat4 viewProjection = frame.projection * frame.view;
    const auto count = static_cast<GLsizei>(instances.size());
    g.Disable(
        GL_CULL_FACE);  // leaves are two-sided; wood is closed, so culling would not change it
    mLeafProgram.use();
    setCommonUniforms(mLeafProgram, frame, viewProjection);
    mLeafProgram.set("uLeafImages", 0);
    g.BindVertexArray(mLeafVao.id());
    bindInstanceMatrices(frame.instanceBuffer, 4);
    g.ActiveTexture(GL_TEXTURE0);
    for (const DrawRange& range : mLeafRanges) {
      const gl::Texture& texture = mLeafGpuTextures[range.material];
      mLeafProgram.set("uBackLayer", float(texture.desc.layers - 1));
      g.BindTexture(GL_TEXTURE_2D_ARRAY, texture.id());
      g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                              reinterpret_cast<const void*>(sizeof(uint32_t) * range.first), count);
    }
    if (mParams.drawWood && !mWoodRanges.empty()) {
      mWoodProgram.use();
      setCommonUniforms(mWoodProgram, frame, viewProjection);
      mWoodProgram.set("uWoodTexture", 0);
      g.BindVertexArray(mWoodVao.id());
      bindInstanceMatrices(frame.instanceBuffer, 4);
      for (const DrawRange& range : mWoodRanges) {
        const WoodMaterial& material = mWoodMaterials[range.material];
        const glm::vec3 linear(srgbToLinear(material.baseColor.r),
                               srgbToLinear(material.baseColor.g),
                               srgbToLinear(material.baseColor.b));
        mWoodProgram.set("uBaseColor", linear);
        mWoodProgram.set("uHasTexture", material.texture >= 0 ? 1 : 0);
        if (material.texture >= 0)
          g.BindTexture(GL_TEXTURE_2D, mWoodGpuTextures[material.texture].id());
        g.DrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                                reinterpret_cast<const void*>(sizeof(uint32_t) * range.first),
                                count);
      }
    }
    g.BindVertexArray(0);
  }

  nlohmann::json effectiveParams() const override { return writeParams(mParams); }

  void save(AssetFolder& asset) const override {
    auto& header = asset.header();
    header["method"] = "polygonal";
    header["params"] = effectiveParams();
    asset.writeBlob("wood_vertices.bin", mWoodVertices);
    asset.writeBlob("wood_indices.bin", mWoodIndices);
    asset.writeBlob("wood_ranges.bin", mWoodRanges);
    asset.writeBlob("leaf_vertices.bin", mLeafVertices);
    asset.writeBlob("leaf_indices.bin", mLeafIndices);
    asset.writeBlob("leaf_ranges.bin", mLeafRanges);
    header["wood_materials"] = nlohmann::json::array();
    for (const WoodMaterial& m : mWoodMaterials) {
      header["wood_materials"].push_back(
          {{"name", m.name},
           {"base_color", {m.baseColor.r, m.baseColor.g, m.baseColor.b, m.baseColor.a}},
           {"texture", m.texture}});
    }
    for (size_t i = 0; i < mWoodTextures.size(); ++i)
      asset.writeImage(fmt::format("wood_{}.png", i), mWoodTextures[i]);
    header["wood_textures"] = mWoodTextures.size();
    for (size_t i = 0; i < mLeafTextures.size(); ++i) {
      asset.writeImage(fmt::format("leaf_{}_front.png", i), mLeafTextures[i].first);
      asset.writeImage(fmt::format("leaf_{}_back.png", i), mLeafTextures[i].second);
    }
    header["leaf_textures"] = mLeafTextures.size();
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    asset.readHeader();
    const auto& header = asset.header();
    if (header.value("method", "") != "polygonal") {
      throwInputError("{}: not a polygonal asset", asset.folder().string());
    }
    mWoodVertices = asset.readBlobAs<Vertex>("wood_vertices.bin");
    mWoodIndices = asset.readBlobAs<uint32_t>("wood_indices.bin");
    mWoodRanges = asset.readBlobAs<DrawRange>("wood_ranges.bin");
    mLeafVertices = asset.readBlobAs<Vertex>("leaf_vertices.bin");
    mLeafIndices = asset.readBlobAs<uint32_t>("leaf_indices.bin");
    mLeafRanges = asset.readBlobAs<DrawRange>("leaf_ranges.bin");
    mWoodMaterials.clear();
    for (const auto& m : header.at("wood_materials")) {
      const auto& c = m.at("base_color");
      mWoodMaterials.push_back({m.at("name"), glm::vec4(c[0], c[1], c[2], c[3]), m.at("texture")});
    }
    mWoodTextures.clear();
    for (size_t i = 0; i < header.at("wood_textures").get<size_t>(); ++i) {
      mWoodTextures.push_back(asset.readImage(fmt::format("wood_{}.png", i)));
    }
    mLeafTextures.clear();
    for (size_t i = 0; i < header.at("leaf_textures").get<size_t>(); ++i) {
      mLeafTextures.push_back({asset.readImage(fmt::format("leaf_{}_front.png", i)),
                               asset.readImage(fmt::format("leaf_{}_back.png", i))});
    }
    validateLoaded(asset.folder().string());
  }

 private:
  void validateLoaded(const std::string& folder) const {
    const auto checkRanges = [&](const std::vector<DrawRange>& ranges, size_t indices,
                                 size_t materials) {
      for (const DrawRange& r : ranges) {
        if (size_t(r.first) + r.count > indices || r.material >= materials) {
          throwInputError("{}: corrupt draw range in polygonal asset", folder);
        }
      }
    };
    checkRanges(mWoodRanges, mWoodIndices.size(), mWoodMaterials.size());
    checkRanges(mLeafRanges, mLeafIndices.size(), mLeafTextures.size());
    for (uint32_t i : mWoodIndices)
      if (i >= mWoodVertices.size()) throwInputError("{}: corrupt wood indices", folder);
    for (uint32_t i : mLeafIndices)
      if (i >= mLeafVertices.size()) throwInputError("{}: corrupt leaf indices", folder);
  }

  static gl::VertexArray makeVertexArray(const gl::Buffer& vertices, const gl::Buffer& indices) {
    const gl::Api& g = gl::api();
    GLuint id = 0;
    g.GenVertexArrays(1, &id);
    gl::VertexArray vao{gl::GlName<gl::deleteVertexArrayName>(id)};
    g.BindVertexArray(id);
    g.BindBuffer(GL_ARRAY_BUFFER, vertices.id());
    g.EnableVertexAttribArray(0);
    g.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, position)));
    g.EnableVertexAttribArray(1);
    g.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, normal)));
    g.EnableVertexAttribArray(2);
    g.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, uv)));
    g.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices.id());
    g.BindVertexArray(0);
    g.BindBuffer(GL_ARRAY_BUFFER, 0);
    return vao;
  }

  static void setCommonUniforms(const gl::Program& program, const FrameContext& frame,
                                const glm::mat4& viewProjection) {
    program.set("uViewProjection", viewProjection);
    program.set("uLit", frame.shading == Shading::kLit ? 1 : 0);
    program.set("uLightDirection", frame.lightDirection);
    program.set("uAmbient", frame.ambient);
  }

  PolygonalParams mParams;
  std::vector<Vertex> mWoodVertices, mLeafVertices;
  std::vector<uint32_t> mWoodIndices, mLeafIndices;
  std::vector<DrawRange> mWoodRanges, mLeafRanges;
  std::vector<WoodMaterial> mWoodMaterials;
  std::vector<ImageRgba8> mWoodTextures;
  std::vector<std::pair<ImageRgba8, ImageRgba8>> mLeafTextures;  // front, back
  gl::Buffer mWoodVbo, mWoodIbo, mLeafVbo, mLeafIbo;
  gl::VertexArray mWoodVao, mLeafVao;
  std::vector<gl::Texture> mLeafGpuTextures, mWoodGpuTextures;
  gl::Program mLeafProgram, mWoodProgram;
};

}  // namespace

void registerPolygonal(MethodRegistry& registry) {
  registry.add(
      {"polygonal", "the reference: wood mesh and every leaf quad with alpha test",
       [](const nlohmann::json& params, const std::string& path) -> std::unique_ptr<Method> {
         return std::make_unique<Polygonal>(readParams<PolygonalParams>(params, path, "polygonal"));
       }});
}

}  // namespace canopy
