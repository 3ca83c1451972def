#include "methods/multilayer_indirect/multilayer_indirect.h"

#include <tbb/parallel_for.h>

#include "common/config.h"
#include "methods/common/ambient_occlusion.h"
#include "methods/common/cloud_levels.h"
#include "methods/common/cloud_params.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/leaf_orientations.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/multilayer_indirect/layered_billboard.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct MultilayerParams {
  CloudParams cloud;
  int hashResolution = 32;
  int maxLayers = 16;
  std::string sprite = "paper";
  OrientationBins bins;
  int leafImageSize = 64;
  float lodFactor = 1.0f;
  int lowResTexelsPerCell = 1;
  bool ambientOcclusion = true;
  int aoRays = 32;
  std::string compression = "none";
  std::string listsPrecision = "float16";
  WoodParams wood;

  template <class Visitor>
  void visit(Visitor& v) {
    cloud.visit(v);
    v("hash_resolution", hashResolution, 1, 1024,
      "hash cells along each billboard's longer side (the memory knob)");
    v("max_layers", maxLayers, 1, 255, "longest list kept per cell (front-most first)");
    v("sprite", sprite, {"paper", "bounds"}, "point-sprite size: the §4.2 formula or the bounds");
    bins.visit(v);
    v("leaf_image_size", leafImageSize, 4, 512, "texels per side of each oriented leaf image");
    v("lod_factor", lodFactor, 0.0f, 1000.0f,
      "shader LoD: list entries walked = factor × projected hash-texel diagonal (px); 0: all");
    v("lowres_texels_per_cell", lowResTexelsPerCell, 1, 16,
      "low-resolution texture texels per hash cell side");
    v("ambient_occlusion", ambientOcclusion,
      "Embree AO of the polygonal tree at sprite corners, for lit frames (§5.2)");
    v("ao_rays", aoRays, 1, 4096, "rays per leaf corner for the ambient occlusion");
    v("compression", compression, {"none", "dxt1", "dxt5"},
      "colour textures: uncompressed, BC1 or BC3 (S3TC)");
    v("lists_precision", listsPrecision, {"float16", "8bit"},
      "Lists Texture entries: RGBA16F positions, or RGBA8 cell-relative positions and sizes "
      "with 4-bit AO (half the memory; the paper's Table 1 budgets)");
    wood.visit(v);
  }
};

struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 lowResUv;  // location 2: the far level's mesh.vert reads it as its uv
  glm::vec2 uv;        // over the billboard
  glm::ivec4 hash;     // first cell in the hash atlas, cells
  glm::vec2 halfExtents;
  glm::vec3 tangent;  // the billboard's axisU: with the normal, the frame leaf normals live in
};

// The asset header's own part.
struct AssetFields {
  glm::ivec2 hashSize{0};
  int listsHeight = 0;
  size_t leafImages = 0;
  float positionRange = 0.0f;  // 8-bit lists: the cell-relative position range
  float maxSpriteSize = 0.0f;  // 8-bit lists: the size quantization's top
  bool lowResOcclusion = false;
  template <class V>
  void visit(V& v) {
    v("hash_size", hashSize);
    v("lists_height", listsHeight);
    v("leaf_images", leafImages);
    v("position_range", positionRange);
    v("max_sprite_size", maxSpriteSize);
    v("lowres_occlusion", lowResOcclusion);
  }
};

constexpr int kListsWidth = 2048;
constexpr int kFarLevel = 2;  // the K/10 cloud draws the low-resolution texture only (§5.1, §6)

class MultilayerIndirect final : public Method {
 public:
  explicit MultilayerIndirect(MultilayerParams params) : mParams(std::move(params)) {
    mParams.cloud.validate("multilayer_indirect");
  }

  void bake(const Tree& tree, BakeContext& ctx) override {
    mLevels = {};
    mLevels.treeBounds = tree.bounds;
    mWood.bake(tree, mParams.wood.levels());
    const uint32_t imageCount = orientedImageCount(tree.leafTextures.size(), mParams.bins);
    if (imageCount > 2048) {
      throwInputError(
          "multilayer_indirect: {} oriented leaf images (textures × 2 × tilts × rotations) exceed "
          "2048; "
          "lower 'rotations' or 'tilts'",
          imageCount);
    }
    const auto clouds = buildBillboardCloudFamily(tree, mParams.cloud.clustering,
                                                  mParams.cloud.divisors(), ctx.seed);
    LayeringParams layering;
    layering.hashResolution = mParams.hashResolution;
    layering.maxLayers = mParams.maxLayers;
    layering.sprite = parseSpriteRule(mParams.sprite);
    layering.bins = mParams.bins;
    std::vector<const Billboard*> billboards;
    for (const BillboardCloud& cloud : clouds) {
      mLevels.addLevel(billboards.size(), cloud.billboards.size());
      for (const Billboard& billboard : cloud.billboards) billboards.push_back(&billboard);
    }
    std::vector<glm::vec4> occlusion;
    if (mParams.ambientOcclusion)
      occlusion = computeLeafCornerOcclusion(tree, mParams.aoRays, ctx.seed);
    std::vector<LayeredBillboard> layered(billboards.size());
    tbb::parallel_for(size_t(0), billboards.size(), [&](size_t i) {
      layered[i] = buildLayeredBillboard(tree, *billboards[i], layering,
                                         mParams.ambientOcclusion ? &occlusion : nullptr);
    });
    const LeafImageSampler sampler(tree);
    mLeafImages = buildOrientedLeafImages(tree, sampler, mParams.bins, mParams.leafImageSize);

    // Hash atlas and lists atlas (§6).
    std::vector<glm::ivec2> cellSizes;
    // The far cloud draws its low-resolution texture only: it needs no hash cells or lists.
    const size_t layeredBillboards =
        mLevels.ranges.size() > kFarLevel ? mLevels.ranges[kFarLevel].first / 6 : layered.size();
    for (size_t i = 0; i < layered.size(); ++i)
      cellSizes.push_back(i < layeredBillboards ? layered[i].cells : glm::ivec2(1));
    const AtlasLayout hashLayout = packAtlas(cellSizes, 0, 1);
    mHashSize = {hashLayout.width, hashLayout.height};
    mHash.assign(size_t(hashLayout.width) * hashLayout.height, 0u);
    mLists.clear();
    mAmbient.clear();
    size_t maxList = 0, dropped = 0, finestEntries = 0;
    for (size_t i = 0; i < layeredBillboards; ++i) {
      const LayeredBillboard& l = layered[i];
      const auto base = static_cast<uint32_t>(mLists.size() / 4);
      for (const LayerEntry& e : l.entries) {
        // The image index, negative (−index − 1) when the leaf's normal leans the other way.
        const float image = e.roll > 0 ? float(e.image) : -float(e.image) - 1.0f;
        mLists.insert(mLists.end(), {e.position.x, e.position.y, e.size, image});
        for (int c = 0; c < 4; ++c)
          mAmbient.push_back(static_cast<uint8_t>(std::lround(e.ambient[c] * 255.0f)));
      }
      for (int y = 0; y < l.cells.y; ++y) {
        for (int x = 0; x < l.cells.x; ++x) {
          const size_t cell = size_t(y) * l.cells.x + x;
          if (l.listLength[cell] == 0) continue;
          maxList = std::max<size_t>(maxList, l.listLength[cell]);
          mHash[size_t(hashLayout.origins[i].y + y) * hashLayout.width + hashLayout.origins[i].x +
                x] = ((base + l.listStart[cell]) << 8) | l.listLength[cell];
        }
      }
      dropped += l.droppedEntries;
      if (i < clouds[0].billboards.size()) finestEntries += l.entries.size();
    }
    if (mLists.size() / 4 >= (1u << 24))
      throwInputError("multilayer_indirect: more than 2^24 list entries");
    mListsHeight = static_cast<int>((mLists.size() / 4 + kListsWidth - 1) / kListsWidth);
    mLists.resize(size_t(kListsWidth) * std::max(mListsHeight, 1) * 4, 0.0f);
    mAmbient.resize(mLists.size(), 255);
    mListsHeight = std::max(mListsHeight, 1);
    if (mParams.listsPrecision == "8bit") quantizeLists(layered, layeredBillboards);

    // The low-resolution texture, baked from the layered representation (§5.1).
    std::vector<ImageRgba8> lowRes(billboards.size()), lowResOcclusion(billboards.size());
    tbb::parallel_for(size_t(0), billboards.size(), [&](size_t i) {
      lowRes[i] = captureLayers(*billboards[i], layered[i], &lowResOcclusion[i]);
    });
    const ImageAtlas atlas = composeAtlas(lowRes, 4, 8);
    mLowRes = atlas.image;
    // §5.2 gives the far level its AO in the low-resolution texture's alpha; that alpha is the
    // alpha-tested coverage here (filtered and mipmapped), and AO written into it moves the
    // silhouette, so the AO gets its own single-channel texture at a quarter of the resolution
    // in each axis (AO is smooth; 1/16 of the atlas' texels), laid out like the colour atlas.
    mLowResOcclusion = {};
    if (mParams.ambientOcclusion) {
      constexpr int kFactor = 4;
      const ImageRgba8 full = composeAtlas(lowResOcclusion, 4, 8).image;
      mLowResOcclusion = ImageRgba8(std::max(1, (full.width + kFactor - 1) / kFactor),
                                    std::max(1, (full.height + kFactor - 1) / kFactor));
      for (int y = 0; y < mLowResOcclusion.height; ++y)
        for (int x = 0; x < mLowResOcclusion.width; ++x) {
          int sum = 0, count = 0;
          for (int dy = 0; dy < kFactor; ++dy)
            for (int dx = 0; dx < kFactor; ++dx) {
              const int sx = kFactor * x + dx, sy = kFactor * y + dy;
              if (sx >= full.width || sy >= full.height) continue;
              sum += full.at(sx, sy)[0];
              ++count;
            }
          uint8_t* out = mLowResOcclusion.at(x, y);
          out[0] = out[1] = out[2] = uint8_t((sum + count / 2) / std::max(count, 1));
          out[3] = 255;
        }
    }

    mVertices.clear();
    mIndices.clear();
    static constexpr int kU[4] = {0, 1, 1, 0}, kV[4] = {0, 0, 1, 1};
    for (size_t i = 0; i < billboards.size(); ++i) {
      const auto base = static_cast<uint32_t>(mVertices.size());
      for (int c = 0; c < 4; ++c) {
        mVertices.push_back({billboards[i]->corner(c), billboards[i]->normal, atlas.cornerUv(i, c),
                             glm::vec2(kU[c], kV[c]),
                             glm::ivec4(hashLayout.origins[i], layered[i].cells),
                             billboards[i]->halfExtents, billboards[i]->axisU});
      }
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
    }
    mReport = {{"clouds", describeClouds(clouds)},
               {"hash_atlas", {hashLayout.width, hashLayout.height}},
               {"list_entries", mLists.size() / 4},
               {"list_entries_finest_level", finestEntries},
               {"longest_list", maxList},
               {"dropped_entries", dropped},
               {"leaf_images", mLeafImages.size()},
               {"lowres_atlas", {atlas.layout.width, atlas.layout.height}}};
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices,
                               "billboard vertices");
    mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mIndices,
                               "billboard indices");
    makeVertexArray();
    mHashTexture = device.createTexture({GL_TEXTURE_2D, mHashSize.x, mHashSize.y, 1, GL_R32UI,
                                         false, MemoryCategory::kTexture, "hash atlas"});
    device.uploadTexture(mHashTexture, GL_RED_INTEGER, GL_UNSIGNED_INT, mHash.data());
    gl::setTextureSampling(mHashTexture, false, false);
    if (packed()) {
      mListsTexture = device.createTexture({GL_TEXTURE_2D, kListsWidth, mListsHeight, 1, GL_RGBA8,
                                            false, MemoryCategory::kTexture, "lists (8-bit)"});
      device.uploadTexture(mListsTexture, GL_RGBA, GL_UNSIGNED_BYTE, mListsPacked.data());
      mAmbientTexture =
          device.createTexture({GL_TEXTURE_2D, kListsWidth, mListsHeight, 1, GL_RGBA4, false,
                                MemoryCategory::kTexture, "ambient occlusion (4-bit)"});
      device.uploadTexture(mAmbientTexture, GL_RGBA, GL_UNSIGNED_SHORT_4_4_4_4,
                           mAmbientPacked.data());
    } else {
      mListsTexture = device.createTexture({GL_TEXTURE_2D, kListsWidth, mListsHeight, 1, GL_RGBA16F,
                                            false, MemoryCategory::kTexture, "lists atlas"});
      device.uploadTexture(mListsTexture, GL_RGBA, GL_FLOAT, mLists.data());
      mAmbientTexture = device.createTexture({GL_TEXTURE_2D, kListsWidth, mListsHeight, 1, GL_RGBA8,
                                              false, MemoryCategory::kTexture,
                                              "ambient occlusion (indexed like the lists)"});
      device.uploadTexture(mAmbientTexture, GL_RGBA, GL_UNSIGNED_BYTE, mAmbient.data());
    }
    gl::setTextureSampling(mListsTexture, false, false);
    gl::setTextureSampling(mAmbientTexture, false, false);
    mLeavesTexture = uploadLeafImageArray(device, mLeafImages, "oriented leaf images",
                                          parseCompression(mParams.compression));
    mLowResTexture = uploadAlphaTestedTexture(device, mLowRes, true, "low-resolution atlas",
                                              parseCompression(mParams.compression));
    if (!mLowResOcclusion.empty()) {
      std::vector<uint8_t> red(size_t(mLowResOcclusion.width) * mLowResOcclusion.height);
      for (size_t i = 0; i < red.size(); ++i) red[i] = mLowResOcclusion.pixels[i * 4];
      mLowResOcclusionTexture = device.createTexture(
          {GL_TEXTURE_2D, mLowResOcclusion.width, mLowResOcclusion.height, 1, GL_R8, true,
           MemoryCategory::kTexture, "low-resolution ambient occlusion"});
      gl::api().PixelStorei(GL_UNPACK_ALIGNMENT, 1);
      device.uploadTexture(mLowResOcclusionTexture, GL_RED, GL_UNSIGNED_BYTE, red.data());
      gl::api().PixelStorei(GL_UNPACK_ALIGNMENT, 4);
      device.generateMipmaps(mLowResOcclusionTexture);
      gl::setTextureSampling(mLowResOcclusionTexture, true, false);
    }
    mProgram = device.createProgram(
        {gl::embeddedShader("methods/multilayer_indirect/multilayer_indirect.vert"),
         gl::embeddedShader("methods/multilayer_indirect/multilayer_indirect.frag")});
    mFarProgram =
        device.createProgram({gl::embeddedShader("methods/common/mesh.vert"),
                              gl::embeddedShader("methods/common/alpha_tested_texture.frag")});
    mLod.attach(device, device.owner() + "/frame");
    if (mParams.wood.draw) mWood.upload(device, true);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    mLod.update(frame, instances, mLevels.treeBounds, mParams.cloud.thresholds());
    const gl::Api& g = gl::api();
    g.BindVertexArray(mVao.id());
    mLevels.draw(mLod, [&](size_t level) {
      const bool far = level >= kFarLevel;
      const gl::Program& program = far ? mFarProgram : mProgram;
      program.use();
      setFrameUniforms(program, frame);
      if (far) {
        program.set("uAtlas", 0);
        program.set("uOcclusion", 1);
        program.set("uHasOcclusion", mLowResOcclusionTexture.id() ? 1 : 0);
        g.ActiveTexture(GL_TEXTURE1);
        g.BindTexture(GL_TEXTURE_2D, mLowResOcclusionTexture.id());
        g.ActiveTexture(GL_TEXTURE0);
        g.BindTexture(GL_TEXTURE_2D, mLowResTexture.id());
      } else {
        bindLayeredTextures(program);
        program.set("uTargetPixelsPerOutputPixel", frame.targetPixelsPerOutputPixel);
      }
    });
    g.ActiveTexture(GL_TEXTURE0);
    g.BindVertexArray(0);
    if (mParams.wood.draw) mWood.draw(frame, instances, mParams.wood.errorPixels);
  }

  uint64_t lodSignature() const override {
    return fnv1aMix(mLod.signature(), mWood.lodSignature());
  }
  std::vector<uint64_t> woodInstancesPerLevel() const override { return mWood.instancesPerLevel(); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mWood.withLevels(mReport); }

  void save(AssetFolder& asset) const override {
    asset.describe("multilayer_indirect", effectiveParams(), mReport);
    mLevels.save(asset);
    asset.writeFields(AssetFields{mHashSize, mListsHeight, mLeafImages.size(), mPositionRange,
                                  mMaxSpriteSize, !mLowResOcclusion.empty()});
    // What the GPU holds is what is stored: the 8-bit lists replace the float ones on disk too.
    if (packed()) {
      asset.writeBlob("lists_8bit.bin", mListsPacked);
      asset.writeBlob("ambient_4bit.bin", mAmbientPacked);
    } else {
      asset.writeBlob("lists.bin", mLists);
      asset.writeBlob("ambient.bin", mAmbient);
    }
    asset.writeBlob("vertices.bin", mVertices);
    asset.writeBlob("indices.bin", mIndices);
    asset.writeBlob("hash.bin", mHash);
    asset.writeImages("leaf_image_{}.png", mLeafImages);
    asset.writeImage("lowres.png", mLowRes);
    if (!mLowResOcclusion.empty()) asset.writeImage("lowres_occlusion.png", mLowResOcclusion);
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("multilayer_indirect");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    mHashSize = fields.hashSize;
    mListsHeight = fields.listsHeight;
    mVertices = asset.readBlobAs<Vertex>("vertices.bin");
    mIndices = asset.readBlobAs<uint32_t>("indices.bin");
    mHash = asset.readBlobAs<uint32_t>("hash.bin");
    mPositionRange = fields.positionRange;
    mMaxSpriteSize = fields.maxSpriteSize;
    if (packed()) {
      mListsPacked = asset.readBlobAs<uint8_t>("lists_8bit.bin");
      mAmbientPacked = asset.readBlobAs<uint16_t>("ambient_4bit.bin");
      if (mAmbientPacked.size() * 4 != mListsPacked.size())
        throwInputError("{}: 8-bit lists and AO blobs differ in length", folder);
      // The float lists stand in for sizes and image checks only: images from the packed ones.
      mLists.assign(mListsPacked.size(), 0.0f);
      for (size_t i = 3; i < mLists.size(); i += 4) mLists[i] = float(mListsPacked[i] & 0x7f);
      mAmbient.clear();
    } else {
      mLists = asset.readBlobAs<float>("lists.bin");
      mAmbient = asset.readBlobAs<uint8_t>("ambient.bin");
    }
    mLeafImages = asset.readImages("leaf_image_{}.png", fields.leafImages);
    mLowRes = asset.readImage("lowres.png");
    mLowResOcclusion =
        fields.lowResOcclusion ? asset.readImage("lowres_occlusion.png") : ImageRgba8();
    if (mHashSize.x < 0 || mHashSize.y < 0 || mListsHeight < 1 ||
        mHash.size() != size_t(mHashSize.x) * mHashSize.y ||
        mLists.size() != size_t(kListsWidth) * mListsHeight * 4) {
      throwInputError("{}: hash or lists blob has the wrong size", folder);
    }
    for (uint32_t packed : mHash) {
      if (packed != 0 && size_t(packed >> 8) + (packed & 255u) > mLists.size() / 4)
        throwInputError("{}: hash cell points past the lists", folder);
    }
    for (size_t i = 3; i < mLists.size(); i += 4) {
      const float image = mLists[i] < 0.0f ? -mLists[i] - 1.0f : mLists[i];
      if (image >= float(mLeafImages.size()) + 0.5f)
        throwInputError("{}: list entry names a missing leaf image", folder);
    }
    validateIndices(mIndices, mVertices.size(), asset.folder().string());
    mLevels.load(asset, mIndices.size());
    mWood.load(asset);
    asset.finishReading();
  }

 private:
  bool packed() const { return mParams.listsPrecision == "8bit"; }

  // lists_precision "8bit": each entry's position relative to its own hash cell (in cells) and
  // its size as a fraction of the largest, in 8 bits; the image index in 8 bits; AO in 4 bits.
  void quantizeLists(const std::vector<LayeredBillboard>& layered, size_t layeredBillboards) {
    const size_t entries = mLists.size() / 4;
    std::vector<glm::vec2> relative(entries, glm::vec2(0.5f));
    mPositionRange = 0.0f;
    mMaxSpriteSize = 1e-12f;
    size_t base = 0;
    for (size_t i = 0; i < layeredBillboards; ++i) {
      const LayeredBillboard& l = layered[i];
      const glm::vec2 half = l.cellSize * glm::vec2(l.cells) * 0.5f;
      for (int y = 0; y < l.cells.y; ++y) {
        for (int x = 0; x < l.cells.x; ++x) {
          const size_t cell = size_t(y) * l.cells.x + x;
          for (uint32_t k = 0; k < l.listLength[cell]; ++k) {
            const size_t e = base + l.listStart[cell] + k;
            const glm::vec2 origin = -half + glm::vec2(x, y) * l.cellSize;
            relative[e] = (glm::vec2(mLists[e * 4], mLists[e * 4 + 1]) - origin) / l.cellSize;
            mPositionRange = std::max({mPositionRange, -relative[e].x, -relative[e].y,
                                       relative[e].x - 1.0f, relative[e].y - 1.0f});
          }
        }
      }
      base += l.entries.size();
    }
    for (size_t e = 0; e < entries; ++e)
      mMaxSpriteSize = std::max(mMaxSpriteSize, mLists[e * 4 + 2]);
    const auto unorm = [](float v) {
      return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
    };
    mListsPacked.assign(mLists.size(), 0);
    mAmbientPacked.assign(mLists.size() / 4, 0xffff);
    for (size_t e = 0; e < entries; ++e) {
      const float stored = mLists[e * 4 + 3];
      const bool leansBack = stored < 0.0f;
      const float image = leansBack ? -stored - 1.0f : stored;
      if (image > 127.0f)
        throwInputError(
            "multilayer_indirect: lists_precision \"8bit\" holds at most 128 leaf images (lower "
            "'rotations' or 'tilts')");
      const glm::vec2 q = (relative[e] + mPositionRange) / (1.0f + 2.0f * mPositionRange);
      mListsPacked[e * 4] = unorm(q.x);
      mListsPacked[e * 4 + 1] = unorm(q.y);
      mListsPacked[e * 4 + 2] = std::max<uint8_t>(1, unorm(mLists[e * 4 + 2] / mMaxSpriteSize));
      mListsPacked[e * 4 + 3] = uint8_t(uint8_t(std::lround(image)) | (leansBack ? 0x80 : 0));
      uint16_t word = 0;
      for (int c = 0; c < 4; ++c)
        word = uint16_t(word << 4 | uint16_t(std::lround(mAmbient[e * 4 + c] / 255.0f * 15.0f)));
      mAmbientPacked[e] = word;
    }
  }

  // What the full walk shows from the billboard's front, at lowres_texels_per_cell texels per
  // hash cell, 4×4 samples per texel: colour (linear mean) and coverage.
  // `occlusion` (optional) gets the mean AO of the leaves hit, 1 where nothing is.
  ImageRgba8 captureLayers(const Billboard& billboard, const LayeredBillboard& layered,
                           ImageRgba8* occlusion = nullptr) const {
    constexpr int kSamples = 4;
    const glm::ivec2 size = layered.cells * mParams.lowResTexelsPerCell;
    ImageRgba8 image(size.x, size.y);
    if (occlusion) *occlusion = ImageRgba8(size.x, size.y);
    for (int y = 0; y < size.y; ++y) {
      for (int x = 0; x < size.x; ++x) {
        glm::vec3 sum(0.0f);
        float ambient = 0.0f;
        int covered = 0;
        for (int sy = 0; sy < kSamples; ++sy) {
          for (int sx = 0; sx < kSamples; ++sx) {
            const glm::vec2 unit((x + (sx + 0.5f) / kSamples) / size.x,
                                 (y + (sy + 0.5f) / kSamples) / size.y);
            const glm::vec2 point = (unit * 2.0f - 1.0f) * billboard.halfExtents;
            const auto hit = walkLayers(layered, billboard, mLeafImages, mParams.bins, point, true);
            if (!hit) continue;
            sum += glm::vec3(srgbToLinear(hit->color.r), srgbToLinear(hit->color.g),
                             srgbToLinear(hit->color.b));
            const glm::vec4& corners = layered.entries[hit->entry].ambient;
            ambient += 0.25f * (corners.x + corners.y + corners.z + corners.w);
            ++covered;
          }
        }
        writeCoverageTexel(image.at(x, y), sum, covered, kSamples * kSamples);
        if (occlusion) {
          uint8_t* out = occlusion->at(x, y);
          const float value = covered ? ambient / float(covered) : 1.0f;
          out[0] = out[1] = out[2] = uint8_t(std::lround(255.0f * value));
          out[3] = image.at(x, y)[3];
        }
      }
    }
    return image;
  }

  void makeVertexArray() {
    const gl::Api& g = gl::api();
    mVao = gl::createVertexArray();
    g.BindBuffer(GL_ARRAY_BUFFER, mVbo.id());
    const auto attribute = [&](GLuint location, GLint components, size_t offset) {
      g.EnableVertexAttribArray(location);
      g.VertexAttribPointer(location, components, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                            reinterpret_cast<const void*>(offset));
    };
    attribute(0, 3, offsetof(Vertex, position));
    attribute(1, 3, offsetof(Vertex, normal));
    attribute(2, 2, offsetof(Vertex, lowResUv));
    attribute(3, 2, offsetof(Vertex, uv));
    g.EnableVertexAttribArray(8);
    g.VertexAttribIPointer(8, 4, GL_INT, sizeof(Vertex),
                           reinterpret_cast<const void*>(offsetof(Vertex, hash)));
    attribute(9, 2, offsetof(Vertex, halfExtents));
    attribute(10, 3, offsetof(Vertex, tangent));
    g.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, mIbo.id());
    g.BindVertexArray(0);
    g.BindBuffer(GL_ARRAY_BUFFER, 0);
  }

  void bindLayeredTextures(const gl::Program& program) const {
    const gl::Api& g = gl::api();
    program.set("uHash", 0);
    program.set("uLists", 1);
    program.set("uLeaves", 2);
    program.set("uLowRes", 3);
    program.set("uAmbientOcclusion", 4);
    program.set("uListsWidth", kListsWidth);
    program.set("uImagesPerSide", mParams.bins.tilts * mParams.bins.rotations);
    program.set("uRotations", mParams.bins.rotations);
    program.set("uTilts", mParams.bins.tilts);
    program.set("uLodFactor", mParams.lodFactor);
    program.set("uListsPacked", packed() ? 1 : 0);
    program.set("uPositionRange", mPositionRange);
    program.set("uMaxSpriteSize", mMaxSpriteSize);
    program.set("uLowResOcclusion", 5);
    program.set("uHasLowResOcclusion", mLowResOcclusionTexture.id() ? 1 : 0);
    g.ActiveTexture(GL_TEXTURE5);
    g.BindTexture(GL_TEXTURE_2D, mLowResOcclusionTexture.id());
    const std::pair<GLenum, GLuint> units[] = {{GL_TEXTURE_2D, mHashTexture.id()},
                                               {GL_TEXTURE_2D, mListsTexture.id()},
                                               {GL_TEXTURE_2D_ARRAY, mLeavesTexture.id()},
                                               {GL_TEXTURE_2D, mLowResTexture.id()},
                                               {GL_TEXTURE_2D, mAmbientTexture.id()}};
    for (GLenum unit = 0; unit < 5; ++unit) {
      g.ActiveTexture(GL_TEXTURE0 + unit);
      g.BindTexture(units[unit].first, units[unit].second);
    }
  }

  MultilayerParams mParams;
  nlohmann::json mReport;
  CloudLevels mLevels;
  std::vector<Vertex> mVertices;
  std::vector<uint32_t> mIndices;
  glm::ivec2 mHashSize{1, 1};
  std::vector<uint32_t> mHash;
  int mListsHeight = 1;
  std::vector<float> mLists;
  std::vector<uint8_t> mAmbient;  // RGBA8 per list entry: ambient term at the sprite's corners
  // lists_precision "8bit": the same entries quantized (RGBA8) and the AO in 4 bits a corner.
  std::vector<uint8_t> mListsPacked;
  std::vector<uint16_t> mAmbientPacked;
  float mPositionRange = 0.0f;  // packed positions span [-range, 1 + range] cells
  float mMaxSpriteSize = 0.0f;  // packed sizes are fractions of this (plane units)
  std::vector<ImageRgba8> mLeafImages;
  ImageRgba8 mLowRes;
  ImageRgba8 mLowResOcclusion;  // AO of the low-resolution atlas at half its resolution (R)
  gl::Buffer mVbo, mIbo;
  gl::VertexArray mVao;
  gl::Texture mHashTexture, mListsTexture, mLeavesTexture, mLowResTexture, mAmbientTexture,
      mLowResOcclusionTexture;
  gl::Program mProgram, mFarProgram;
  LodInstances mLod;
  WoodRenderer mWood;
};

}  // namespace

void registerMultilayerIndirect(MethodRegistry& registry) {
  addMethod<MultilayerIndirect, MultilayerParams>(
      registry, "multilayer_indirect",
      "multi-layer indirect texturing (García et al. 2007): lists of leaf fragments per hash cell",
      {.memoryKnob = MemoryKnob{"hash_resolution", 4, 256, true, true},
       .cost = {.bakeSeconds = 1.2, .frameCost = 1.0}});
}

}  // namespace canopy
