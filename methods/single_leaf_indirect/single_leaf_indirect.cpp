#include "methods/single_leaf_indirect/single_leaf_indirect.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/config.h"
#include "methods/common/cloud_levels.h"
#include "methods/common/cloud_params.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/leaf_orientations.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/single_leaf_indirect/single_leaf_grid.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct SingleLeafParams {
  CloudParams cloud;
  float cellSize = 1.0f;
  int maxCells = 1024;
  OrientationBins bins;
  int leafImageSize = 64;
  int viewOrders = 0;
  float lodLowResPixels = 110.0f;
  int lowResTexelsPerCell = 1;
  WoodParams wood;

  template <class Visitor>
  void visit(Visitor& v) {
    cloud.visit(v);
    v("cell_size", cellSize, 0.05f, 100.0f,
      "grid cell side in mean leaf lengths (the grid resolution; the memory knob); leaves keep "
      "their own size");
    v("max_cells", maxCells, 1, 4096, "cap on cells per billboard side");
    bins.visit(v);
    v("leaf_image_size", leafImageSize, 4, 512, "texels per side of each oriented leaf image");
    v("view_orders", viewOrders, 0, 64,
      "beyond the paper: the billboards are drawn front to back, in the order sorted for the "
      "nearest of this many view directions, so the depth test rejects hidden fragments before "
      "the cell lookup (one draw per direction in use; 24 bytes of indices per billboard and "
      "direction; 0: the bake's order)");
    v("lod_lowres_px", lodLowResPixels, 0.0f, 100000.0f,
      "beyond the 2005 paper, the multi-layer paper's shader level of detail (its §5.1): a tree "
      "whose bounding radius spans fewer output pixels draws its cloud as a low-resolution "
      "texture (each billboard's leaves captured from both sides) instead of the cell lookup; "
      "0: every tree does the lookup");
    v("lowres_texels_per_cell", lowResTexelsPerCell, 1, 8,
      "texels of the low-resolution textures per cell_size cell side");
    wood.visit(v);
  }
};

struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;     // over the billboard
  glm::ivec4 grid;  // first cell in the index atlas, cells
  // The cells a fragment looks at, by how far the billboard's largest leaf reaches past its
  // cell: 0 its own cell, 1 the 2×2 cells nearest the fragment, r + 1 the cells within r.
  int32_t reach;
  glm::vec2 lowResUv;  // in the low-resolution atlas; 0 for clouds never drawn from it
};

// The asset header's own part.
struct AssetFields {
  glm::ivec2 indexSize{0};  // the cell index atlas
  size_t leafImages = 0;
  size_t lowResLayers = 0;  // the low-resolution atlas: 0, or front and back
  template <class V>
  void visit(V& v) {
    v("index_size", indexSize);
    v("leaf_images", leafImages);
    v("lowres_layers", lowResLayers);
  }
};

constexpr int kScaleSteps = 32;  // a leaf's size in cells, in 1/32 steps up to 255/32
constexpr int kMaxRadius = 3;    // larger leaves are clipped to 7×7 cells
constexpr int kLowResPadding = 4, kLowResAlignment = 8;  // of the low-resolution atlas
constexpr int kLowResSupersample = 4;                    // capture samples per texel side
constexpr int kMaxLowResTexels = 1024;                   // per side of one billboard's image

class SingleLeafIndirect final : public Method {
 public:
  explicit SingleLeafIndirect(SingleLeafParams params) : mParams(params) {
    mParams.cloud.resolve("single_leaf_indirect");
  }

  void bake(const Tree& tree, BakeContext& ctx) override {
    mLevels = {};
    mLevels.treeBounds = tree.bounds;
    mWood.bake(tree, mParams.wood.levels());
    if (orientedImageCount(tree.leafTextures.size(), mParams.bins) >= 4095) {
      throwInputError(
          "single_leaf_indirect: rotations × tilts × 2 × leaf textures must stay below 4095");
    }
    const auto clouds = buildBillboardCloudFamily(tree, mParams.cloud.levels(), ctx.seed);
    const float cellLength = mParams.cellSize * meanLeafLength(tree);
    std::vector<SingleLeafGrid> grids;
    std::vector<const Billboard*> billboards;
    for (const BillboardCloud& cloud : clouds) {
      mLevels.addLevel(billboards.size(), cloud.billboards.size());
      for (SingleLeafGrid& grid :
           buildSingleLeafGrids(tree, cloud, cellLength, mParams.bins, mParams.maxCells)) {
        grids.push_back(std::move(grid));
      }
      for (const Billboard& billboard : cloud.billboards) billboards.push_back(&billboard);
    }
    std::vector<glm::ivec2> sizes;
    sizes.reserve(grids.size());
    for (const SingleLeafGrid& grid : grids) sizes.push_back(grid.cells);
    const AtlasLayout layout = packAtlas(sizes, 0, 1);
    if (layout.width > 16384 || layout.height > 16384) {
      throwInputError(
          "single_leaf_indirect: parameter 'cell_size' = {} needs a {}x{} index atlas; raise it",
          mParams.cellSize, layout.width, layout.height);
    }
    mIndexSize = {layout.width, layout.height};
    mIndex.assign(size_t(layout.width) * layout.height, 0u);
    size_t filled = 0, represented = 0;
    std::vector<int32_t> reach(grids.size(), 0);
    std::vector<size_t> billboardsPerReach(kMaxRadius + 2, 0);
    for (size_t i = 0; i < grids.size(); ++i) {
      float largest = 0.0f;
      const SingleLeafGrid& grid = grids[i];
      float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
      for (size_t cell = 0; cell < grid.leaf.size(); ++cell) {
        if (grid.leaf[cell] < 0) continue;
        low = std::min(low, grid.height[cell]);
        high = std::max(high, grid.height[cell]);
      }
      for (int y = 0; y < grid.cells.y; ++y) {
        for (int x = 0; x < grid.cells.x; ++x) {
          const size_t cell = size_t(y) * grid.cells.x + x;
          if (grid.leaf[cell] < 0) continue;
          const auto scale = static_cast<uint32_t>(
              std::clamp(std::lround(grid.scale[cell] * float(kScaleSteps)), 1L, 255L));
          const auto depth = static_cast<uint32_t>(
              std::lround((grid.height[cell] - low) / std::max(high - low, 1e-12f) * 4095.0f));
          mIndex[size_t(layout.origins[i].y + y) * layout.width + layout.origins[i].x + x] =
              (grid.image[cell] + 1) | scale << 12 | depth << 20;
          largest = std::max(largest, float(scale) / float(kScaleSteps));
          ++filled;
        }
      }
      if (i < clouds[0].billboards.size()) represented += grid.leavesPlaced;
      // A leaf of s cell lengths centred on its cell reaches (s − 1) / 2 cells beyond it: not at
      // all (own cell only), half a cell at most (the 2×2 cells nearest the fragment), or more.
      const float beyond = (largest - 1.0f) * 0.5f;
      reach[i] = beyond <= 0.0f   ? 0
                 : beyond <= 0.5f ? 1
                                  : 1 + std::min(kMaxRadius, static_cast<int>(std::ceil(beyond)));
      ++billboardsPerReach[size_t(reach[i])];
    }
    mVertices.clear();
    mIndices.clear();
    static constexpr int kU[4] = {0, 1, 1, 0}, kV[4] = {0, 0, 1, 1};
    for (size_t i = 0; i < billboards.size(); ++i) {
      const auto base = static_cast<uint32_t>(mVertices.size());
      const glm::ivec4 grid(layout.origins[i], grids[i].cells);
      for (int c = 0; c < 4; ++c) {
        mVertices.push_back({billboards[i]->corner(c), billboards[i]->normal,
                             glm::vec2(kU[c], kV[c]), grid, reach[i], glm::vec2(0.0f)});
      }
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
    }
    const LeafImageSampler sampler(tree);
    mLeafImages = buildOrientedLeafImages(tree, sampler, mParams.bins, mParams.leafImageSize);
    setDrawLevels();
    // The clouds some trees draw as textures: each billboard's leaves seen from both sides, at
    // lowres_texels_per_cell texels a grid cell (§5.1 of the multi-layer paper bakes its texture
    // from its own representation; the leaves themselves are what that representation shows).
    const size_t firstTextured = mShaderLod.firstTextureCloud < mLevels.ranges.size()
                                     ? mLevels.ranges[mShaderLod.firstTextureCloud].first / 6
                                     : billboards.size();
    std::vector<const Billboard*> textured(billboards.begin() + long(firstTextured),
                                           billboards.end());
    // Texels from the cell_size cells, not the grid's own (a billboard crowded with leaves halves
    // its cells so that each leaf has one; its texture need not follow).
    std::vector<glm::ivec2> texels;
    for (size_t i = firstTextured; i < billboards.size(); ++i) {
      const glm::vec2 cells = 2.0f * billboards[i]->halfExtents / cellLength;
      texels.push_back(glm::clamp(glm::ivec2(glm::ceil(cells * float(mParams.lowResTexelsPerCell))),
                                  glm::ivec2(1), glm::ivec2(kMaxLowResTexels)));
    }
    mLowRes.clear();
    if (!textured.empty()) {
      TwoSidedAtlas atlas =
          captureTwoSidedAtlas(tree, sampler, textured, texels, kLowResSupersample, true,
                               kLowResPadding, kLowResAlignment);
      mLowRes = {std::move(atlas.front.image), std::move(atlas.back)};
      for (size_t i = firstTextured; i < billboards.size(); ++i) {
        for (int c = 0; c < 4; ++c)
          mVertices[4 * i + size_t(c)].lowResUv = atlas.front.cornerUv(i - firstTextured, c);
      }
    }
    mReport = {{"clouds", describeClouds(clouds)},
               {"index_atlas", {layout.width, layout.height}},
               {"filled_cells", filled},
               {"leaf_images", mLeafImages.size()},
               {"cell_length", cellLength},
               {"leaves_represented", represented},
               {"leaves", tree.leaves.size()},
               {"billboards_per_reach", billboardsPerReach},
               {"lowres_atlas",
                {mLowRes.empty() ? 0 : mLowRes[0].width, mLowRes.empty() ? 0 : mLowRes[0].height}}};
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices,
                               "billboard vertices");
    // view_orders: every level sorted per direction, appended after the bake's indices.
    std::vector<glm::vec3> centers;
    for (size_t i = 0; mParams.viewOrders > 0 && i + 6 <= mIndices.size(); i += 6) {
      glm::vec3 sum(0.0f);
      for (size_t k : {0, 1, 2, 5}) sum += mVertices[mIndices[i + k]].position;
      centers.push_back(0.25f * sum);
    }
    mOrders = mLevels.viewOrders(centers, mShaderLod.lookupLevels, mParams.viewOrders);
    mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER,
                               CloudLevels::withOrderedIndices(mIndices, mOrders),
                               "billboard indices");
    const gl::Api& g = gl::api();
    mVao = gl::createVertexArray();
    g.BindBuffer(GL_ARRAY_BUFFER, mVbo.id());
    g.EnableVertexAttribArray(0);
    g.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, position)));
    g.EnableVertexAttribArray(1);
    g.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, normal)));
    g.EnableVertexAttribArray(2);
    g.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, uv)));
    g.EnableVertexAttribArray(3);
    g.VertexAttribIPointer(3, 4, GL_INT, sizeof(Vertex),
                           reinterpret_cast<const void*>(offsetof(Vertex, grid)));
    g.EnableVertexAttribArray(8);
    g.VertexAttribIPointer(8, 1, GL_INT, sizeof(Vertex),
                           reinterpret_cast<const void*>(offsetof(Vertex, reach)));
    g.EnableVertexAttribArray(9);
    g.VertexAttribPointer(9, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, lowResUv)));
    g.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, mIbo.id());
    g.BindVertexArray(0);
    g.BindBuffer(GL_ARRAY_BUFFER, 0);
    mIndexTexture =
        device.createTexture({GL_TEXTURE_2D, mIndexSize.x, mIndexSize.y, 1, GL_R32UI, false,
                              MemoryCategory::kTexture, "single-leaf index atlas"});
    device.uploadTexture(mIndexTexture, GL_RED_INTEGER, GL_UNSIGNED_INT, mIndex.data());
    gl::setTextureSampling(mIndexTexture, false, false);
    mLeavesTexture = uploadAlphaTestedArray(device, mLeafImages, true, "oriented leaf images");
    const gl::ShaderSource& vertex =
        gl::embeddedShader("methods/single_leaf_indirect/single_leaf_indirect.vert");
    mProgram = device.createProgram(
        {vertex, gl::embeddedShader("methods/single_leaf_indirect/single_leaf_indirect.frag")});
    if (!mLowRes.empty()) {
      mLowResTexture = uploadAlphaTestedArray(device, mLowRes, true, "low-resolution atlas");
      mTextureVertexText = gl::withDefines(vertex.text, "#define LOWRES_TEXTURE 1\n");
      mTextureProgram =
          device.createProgram({{vertex.path, mTextureVertexText},
                                gl::embeddedShader("methods/common/alpha_tested_texture.frag")});
    }
    mLod.attach(device, device.owner() + "/frame");
    if (mParams.wood.draw) mWood.upload(device, true);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    mWood.drawAround(mParams.wood, frame, instances, [&] { drawLeaves(frame, instances); });
  }

  // Everything but the wood (drawAround orders the two).
  void drawLeaves(const FrameContext& frame, std::span<const Instance> instances) {
    const size_t lookups = mShaderLod.lookupLevels;
    mLod.update(frame, instances, mLevels.treeBounds, mShaderLod.thresholds,
                mShaderLod.draw.directionGrouping(mOrders, frame, lookups),
                mOrders.empty() ? 1 : int(mOrders.directions.size()));
    const gl::Api& g = gl::api();
    g.BindVertexArray(mVao.id());
    mShaderLod.draw.draw(
        mLod,
        [&](size_t level) {
          if (level >= lookups) {
            mTextureProgram.use();
            setFrameUniforms(mTextureProgram, frame);
            mTextureProgram.set("uAtlas", 0);
            mTextureProgram.set("uBackLayer", 1.0f);
            mTextureProgram.set("uBinaryAlpha", 0);
            mTextureProgram.set("uAggregateCoverage", 1);
            mTextureProgram.set("uHasOcclusion", 0);
            mTextureProgram.set("uOcclusion", 1);  // unused; off the atlas' unit
            g.ActiveTexture(GL_TEXTURE0);
            g.BindTexture(GL_TEXTURE_2D_ARRAY, mLowResTexture.id());
            return;
          }
          mProgram.use();
          setFrameUniforms(mProgram, frame);
          mProgram.set("uCells", 0);
          mProgram.set("uLeaves", 1);
          mProgram.set("uImagesPerSide", mParams.bins.tilts * mParams.bins.rotations);
          g.ActiveTexture(GL_TEXTURE0);
          g.BindTexture(GL_TEXTURE_2D, mIndexTexture.id());
          g.ActiveTexture(GL_TEXTURE1);
          g.BindTexture(GL_TEXTURE_2D_ARRAY, mLeavesTexture.id());
          g.ActiveTexture(GL_TEXTURE0);
        },
        false,
        [&](size_t level, size_t group) {
          return mOrders.empty() || level >= lookups
                     ? static_cast<GLint>(mShaderLod.draw.ranges[level].first)
                     : static_cast<GLint>(mIndices.size() +
                                          6 * mOrders.firstSlot(int(group), level));
        });
    g.BindVertexArray(0);
  }

  uint64_t lodSignature() const override {
    return fnv1aMix(mLod.signature(), mWood.lodSignature());
  }
  std::vector<uint64_t> woodInstancesPerLevel() const override { return mWood.instancesPerLevel(); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mWood.withLevels(mReport); }

  void save(AssetFolder& asset) const override {
    asset.describe("single_leaf_indirect", effectiveParams(), mReport);
    mLevels.save(asset);
    asset.writeFields(AssetFields{mIndexSize, mLeafImages.size(), mLowRes.size()});
    asset.writeBlob("vertices.bin", mVertices);
    asset.writeBlob("indices.bin", mIndices);
    asset.writeBlob("cell_index.bin", mIndex);
    asset.writeImages("leaf_image_{}.png", mLeafImages);
    asset.writeImages("lowres_{}.png", mLowRes);
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("single_leaf_indirect");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    mIndexSize = fields.indexSize;
    mVertices = asset.readBlobAs<Vertex>("vertices.bin");
    mIndices = asset.readBlobAs<uint32_t>("indices.bin");
    mIndex = asset.readBlobAs<uint32_t>("cell_index.bin");
    for (const Vertex& vertex : mVertices) {
      if (vertex.reach < 0 || vertex.reach > kMaxRadius + 1)
        throwInputError("{}: a billboard's reach {} is outside [0, {}]", folder, vertex.reach,
                        kMaxRadius + 1);
    }
    mLeafImages = asset.readImages("leaf_image_{}.png", fields.leafImages);
    mLowRes = asset.readImages("lowres_{}.png", fields.lowResLayers);
    if (mIndex.size() != size_t(mIndexSize.x) * mIndexSize.y)
      throwInputError("{}: cell index size mismatch", folder);
    for (uint32_t word : mIndex) {
      if ((word & 4095u) > mLeafImages.size())
        throwInputError("{}: cell names leaf image {} of {}", folder, word & 4095u,
                        mLeafImages.size());
    }
    validateIndices(mIndices, mVertices.size(), asset.folder().string());
    mLevels.load(asset, mIndices.size());
    setDrawLevels();
    const bool textured = mShaderLod.firstTextureCloud < mLevels.ranges.size();
    if (textured && (mLowRes.size() != 2 || mLowRes[0].width != mLowRes[1].width ||
                     mLowRes[0].height != mLowRes[1].height))
      throwInputError("{}: lod_lowres_px needs a front and a back low-resolution atlas of one size",
                      folder);
    mWood.load(asset);
    asset.finishReading();
  }

 private:
  // The draw levels: mLevels' clouds, split where lod_lowres_px turns lookups into textures.
  void setDrawLevels() {
    mShaderLod = shaderLodLevels(mLevels, mParams.cloud.thresholds(), mParams.lodLowResPixels);
  }

  SingleLeafParams mParams;
  nlohmann::json mReport;
  CloudLevels mLevels;
  ShaderLodLevels mShaderLod;
  std::vector<Vertex> mVertices;
  std::vector<uint32_t> mIndices;
  ViewOrders mOrders;  // view_orders: empty without
  glm::ivec2 mIndexSize{1, 1};
  // Per cell: 0 empty, else (image + 1) | scale · kScaleSteps << 12 | depth rank << 20.
  std::vector<uint32_t> mIndex;
  std::vector<ImageRgba8> mLeafImages;
  std::vector<ImageRgba8> mLowRes;  // front and back low-resolution atlases, or none
  gl::Buffer mVbo, mIbo;
  gl::VertexArray mVao;
  gl::Texture mIndexTexture, mLeavesTexture, mLowResTexture;
  gl::Program mProgram, mTextureProgram;
  std::string mTextureVertexText;  // the vertex shader with LOWRES_TEXTURE defined
  LodInstances mLod;
  WoodRenderer mWood;
};

}  // namespace

void registerSingleLeafIndirect(MethodRegistry& registry) {
  addMethod<SingleLeafIndirect, SingleLeafParams>(
      registry, "single_leaf_indirect",
      "one leaf image per billboard grid cell (García et al. 2005)",
      {.memoryKnob = MemoryKnob{"cell_size", 0.25, 8, false, false},
       .cost = {.bakeSeconds = 0.6, .frameCost = 0.6}});
}

}  // namespace canopy
