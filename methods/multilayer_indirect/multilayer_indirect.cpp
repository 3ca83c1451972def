#include "methods/multilayer_indirect/multilayer_indirect.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "common/config.h"
#include "methods/common/ambient_occlusion.h"
#include "methods/common/cloud_levels.h"
#include "methods/common/cloud_params.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/leaf_images.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/common/view_orders.h"
#include "methods/common/wood_capture.h"
#include "methods/multilayer_indirect/layered_billboard.h"
#include "methods/multilayer_indirect/list_textures.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct MultilayerParams {
  // K = 1000: broadleaf 20.7 dB at 1.5 radii, coverage error 0.076, against 19.2 dB / 0.099 for
  // K = 400; 60 cells rather than 40: +0.9 dB at 12 radii and a shorter walk, 3.31 MB instead
  // of 2.87 (docs/METHODS.md, "multi-layer defaults").
  CloudParams cloud{.clustering = {.clusters = 1000}};
  int hashResolution = 60;
  int maxLayers = 64;
  int leafImageSize = 64;
  float lodFactor = 1.0f;
  std::string lowResFallback = "all";
  int lowResTexelsPerCell = 1;
  bool ambientOcclusion = true;
  int aoRays = 32;
  std::string compression = "dxt5";
  // BC3 as the paper: uncompressed is faster on llvmpipe (BC3 decode inside the list walk is 30 %
  // of a one-tree frame) but scores 0.3-1.5 dB lower at 4 radii (docs/METHODS.md, "multi-layer
  // speed").
  std::string leafImageCompression = "dxt5";
  std::string listsPrecision = "8bit";
  bool parallax = false;
  float parallaxMaxAngle = 70.0f;
  float lodLowResPixels = 0.0f;
  float woodCapturePixels = 0.0f;
  float woodCaptureFarPixels = 0.0f;
  int viewOrders = 0;
  WoodParams wood;

  template <class Visitor>
  void visit(Visitor& v) {
    cloud.visit(v);
    v("hash_resolution", hashResolution, 1, 8192,
      "hash cells along the tree's bounding-sphere diameter: every billboard's cells are squares "
      "of that size (the memory knob)");
    v("max_layers", maxLayers, 1, 255, "longest list kept per cell (front-most first)");
    v("leaf_image_size", leafImageSize, 4, 512,
      "texels per side of each leaf image (front and back per leaf texture)");
    v("lod_factor", lodFactor, 0.0f, 1000.0f,
      "shader LoD: list entries walked = factor × projected hash-texel diagonal (px); 0: all");
    v("lowres_fallback", lowResFallback, {"all", "rest"},
      "after a shortened walk missed, the low-resolution texel's coverage a as captured, of all "
      "the cell's leaves (§5.1), or of the share not walked only (rest: 1 - (1 - a)^share, "
      "leaves overlapping independently)");
    v("lowres_texels_per_cell", lowResTexelsPerCell, 1, 16,
      "low-resolution texture texels per hash cell side");
    v("ambient_occlusion", ambientOcclusion,
      "Embree AO of the polygonal tree at the leaf corners, for lit frames (§5.2)");
    v("ao_rays", aoRays, 1, 4096, "rays per leaf corner for the ambient occlusion");
    v("compression", compression, {"none", "dxt1", "dxt5"},
      "low-resolution atlas: uncompressed, BC1 or BC3 (S3TC)");
    v("leaf_image_compression", leafImageCompression, {"none", "dxt1", "dxt5"},
      "leaf images (sampled at every step of the list walk): uncompressed, BC1 or BC3");
    v("lists_precision", listsPrecision, {"float16", "8bit"},
      "leaf records: RGBA16F, or RGBA8 (16-bit positions, 8-bit frames) with 4-bit AO");
    v("parallax", parallax,
      "beyond the paper: each fragment follows the view ray to the leaf's own plane, so leaves "
      "show where they are, not where the billboard flattened them, and write their depth");
    v("parallax_max_angle", parallaxMaxAngle, 0.0f, 89.0f,
      "parallax: rays up to this angle from the billboard normal find every leaf they cross "
      "(the billboard and its cells grow by the offsets); steeper rays are bent to it");
    v("lod_lowres_px", lodLowResPixels, 0.0f, 100000.0f,
      "below this projected radius (output pixels) the middle cloud skips the list walk and "
      "draws its low-resolution texture only, as the far cloud does; between lod_far_px and "
      "lod_near_px (0: the walk down to lod_far_px)");
    v("view_orders", viewOrders, 0, 64,
      "beyond the paper: the near and middle clouds' billboards are drawn front to back, in the "
      "order sorted for the nearest of this many view directions, so the depth test rejects "
      "hidden fragments before the list walk (one draw per direction in use; 2 bytes per "
      "billboard and direction; 0: the bake's order)");
    wood.visit(v);
    v("wood_capture_px", woodCapturePixels, 0.0f, 100.0f,
      "the clouds drawn as low-resolution textures only (below lod_lowres_px, or lod_far_px) "
      "also hold the wood lying (every corner) within this many output pixels of one of their "
      "billboards, measured at the largest projected size each is drawn at; trees drawn with "
      "them draw only the rest of the wood as geometry (0: leaves only; 0 in effect without lod "
      "or wood)");
    v("wood_capture_far_px", woodCaptureFarPixels, 0.0f, 100.0f,
      "the far cloud's own bound instead (0: wood_capture_px's): its low-resolution images hold "
      "the wood within this many output pixels of its billboards at its largest projected size "
      "(lod_far_px), and trees drawn with it draw only the rest; a middle cloud drawn as images "
      "(lod_lowres_px) keeps what wood_capture_px gives both (at least wood_capture_px; 0 in "
      "effect without lod or wood)");
  }
};

// A billboard as the vertex shader pulls it (multilayer_indirect.vert), 48 bytes: thousands of
// billboards, and the bytes count against the paper's memory (four 48-byte corners and six
// indices each were a third of it). Pairs of 16-bit values share a word, x in the low half.
struct BillboardRecord {
  glm::vec3 center{0.0f};
  uint32_t normal = 0;          // 2_10_10_10 signed normalized
  glm::vec2 halfExtents{0.0f};  // of the drawn rectangle (grown for parallax)
  uint32_t tangent = 0;         // the billboard's axisU, 2_10_10_10: with the normal, its frame
  uint32_t recordBase = 0;      // the billboard's first leaf record
  uint32_t hashOrigin = 0;      // first cell in the hash atlas
  uint32_t hashCells = 0;       // cells of its hash grid
  uint32_t lowResOrigin = 0;    // first texel of its rectangle in the low-resolution atlas
  uint32_t lowResSize = 0;      // texels of that rectangle
};
static_assert(sizeof(BillboardRecord) == 48);

uint32_t packPair(glm::ivec2 v) {
  return uint32_t(v.x) | (uint32_t(v.y) << 16);
}
glm::ivec2 unpackPair(uint32_t word) {
  return {int(word & 0xffffu), int(word >> 16)};
}

uint32_t packSnorm10(const glm::vec3& v) {
  uint32_t word = 0;
  for (int c = 0; c < 3; ++c) {
    const auto q = static_cast<int32_t>(std::lround(std::clamp(v[c], -1.0f, 1.0f) * 511.0f));
    word |= (uint32_t(q) & 1023u) << (10 * c);
  }
  return word;
}

// The asset header's own part.
struct AssetFields {
  glm::ivec2 hashSize{0};
  int listsHeight = 0;
  bool wideLists = false;
  size_t listEntries = 0;
  size_t records = 0;
  int recordsHeight = 0;
  float axisScale = 0.0f;
  float heightScale = 0.0f;
  size_t leafImages = 0;
  bool lowResBack = false;
  bool lowResOcclusion = false;
  template <class V>
  void visit(V& v) {
    v("hash_size", hashSize);
    v("lists_height", listsHeight);
    v("wide_lists", wideLists);
    v("list_entries", listEntries);
    v("records", records);
    v("records_height", recordsHeight);
    v("axis_scale", axisScale);
    v("height_scale", heightScale);
    v("leaf_images", leafImages);
    v("lowres_back", lowResBack);
    v("lowres_occlusion", lowResOcclusion);
  }
};

constexpr int kLowResPadding = 4, kLowResAlignment = 8;  // of the low-resolution atlas
constexpr int kFarLevel = 2;  // the far cloud draws the low-resolution texture only (§5.1, §6)
constexpr float kPi = 3.14159265358979f;

class MultilayerIndirect final : public Method {
 public:
  explicit MultilayerIndirect(MultilayerParams params) : mParams(std::move(params)) {
    mParams.cloud.resolve("multilayer_indirect");
    const CloudParams& cloud = mParams.cloud;
    if (mParams.lodLowResPixels > 0.0f &&
        (!cloud.lod || mParams.lodLowResPixels <= cloud.lodFarPixels ||
         mParams.lodLowResPixels >= cloud.lodNearPixels))
      throwInputError(
          "multilayer_indirect: parameter 'lod_lowres_px' ({}) must lie between 'lod_far_px' ({}) "
          "and 'lod_near_px' ({}) with 'lod' on, or be 0",
          mParams.lodLowResPixels, cloud.lodFarPixels, cloud.lodNearPixels);
    resolveWoodCapture("multilayer_indirect", cloud.lod, mParams.wood.draw,
                       mParams.woodCapturePixels, mParams.woodCaptureFarPixels);
  }

  void bake(const Tree& tree, BakeContext& ctx) override {
    mLevels = {};
    mLevels.treeBounds = tree.bounds;
    const auto clouds = buildBillboardCloudFamily(tree, mParams.cloud.levels(), ctx.seed);
    // The clouds drawn as low-resolution textures only hold the wood their trees do not draw.
    const std::vector<float> imageLevels = lowResOnlyThresholds();
    const WoodInImages woodInImages = captureWoodInImages(
        tree, clouds, clouds.size() - std::min(clouds.size(), imageLevels.size()), imageLevels,
        mParams.woodCapturePixels, mParams.woodCaptureFarPixels);
    mWood.bake(tree, mParams.wood.levels(), woodInImages.captured);
    const WoodColorSampler woodColors(tree);
    std::vector<const Billboard*> billboards;
    for (const BillboardCloud& cloud : clouds) {
      mLevels.addLevel(billboards.size(), cloud.billboards.size());
      for (const Billboard& billboard : cloud.billboards) billboards.push_back(&billboard);
    }
    // The far cloud draws its low-resolution texture only: it needs no hash cells or lists.
    const size_t withLists =
        mLevels.ranges.size() > kFarLevel ? mLevels.ranges[kFarLevel].first / 6 : billboards.size();
    std::vector<glm::vec4> occlusion;
    if (mParams.ambientOcclusion)
      occlusion = computeLeafCornerOcclusion(tree, mParams.aoRays, ctx.seed);
    const LeafImageSampler sampler(tree);
    const LeafImages leafImages =
        buildLeafImages(tree, sampler, mParams.leafImageSize, packed() ? 256 : 1024);
    mLeafLayers = leafImages.layers;
    std::vector<LayeredBillboard> layered(billboards.size());
    tbb::parallel_for(size_t(0), billboards.size(), [&](size_t i) {
      LayeringParams layering;
      layering.cellSize = 2.0f * tree.boundingSphereRadius() / float(mParams.hashResolution);
      layering.maxLayers = mParams.maxLayers;
      layering.maxSlope = mParams.parallax && i < withLists
                              ? std::tan(mParams.parallaxMaxAngle * kPi / 180.0f)
                              : 0.0f;
      layered[i] = buildLayeredBillboard(tree, *billboards[i], leafImages.imageOfLeaf, layering,
                                         mParams.ambientOcclusion ? &occlusion : nullptr);
    });
    mLists = packListTextures(layered, withLists, packed(), leafImages.count());

    // The low-resolution texture, baked from the layered representation (§5.1), seen from each
    // side of the billboard; and the AO of what the front sees.
    std::vector<ImageRgba8> fronts(billboards.size()), backs(billboards.size()),
        frontOcclusion(billboards.size());
    tbb::parallel_for(size_t(0), billboards.size() * 2, [&](size_t k) {
      const size_t i = k % billboards.size();
      std::optional<LayeredWood> wood;
      if (!woodInImages.perBillboard[i].empty()) {
        wood.emplace(LayeredWood{tree, woodColors, woodInImages.perBillboard[i], *billboards[i]});
        wood->billboard.halfExtents = layered[i].halfExtents;
      }
      const LayeredWood* woodInImage = wood ? &*wood : nullptr;
      if (k < billboards.size()) {
        fronts[i] = captureLayered(layered[i], mLeafLayers, mParams.lowResTexelsPerCell, true,
                                   &frontOcclusion[i], woodInImage);
      } else {
        backs[i] = captureLayered(layered[i], mLeafLayers, mParams.lowResTexelsPerCell, false,
                                  nullptr, woodInImage);
      }
    });
    const ImageAtlas atlas = composeAtlas(fronts, kLowResPadding, kLowResAlignment);
    mLowRes = {atlas.image, composeAtlas(backs, kLowResPadding, kLowResAlignment).image};
    // §5.2 gives the far level its AO in the low-resolution texture's alpha; that alpha is the
    // alpha-tested coverage here (filtered and mipmapped), and AO written into it moves the
    // silhouette, so the AO gets its own single-channel texture at a quarter of the resolution
    // in each axis (AO is smooth; 1/16 of the atlas' texels), laid out like the colour atlas.
    mLowResOcclusion =
        mParams.ambientOcclusion
            ? quarterResolution(
                  composeAtlas(frontOcclusion, kLowResPadding, kLowResAlignment).image)
            : ImageRgba8();
    makeBillboardRecords(billboards, layered, atlas);
    size_t finestEntries = 0;
    for (size_t i = 0; i < clouds[0].billboards.size() && i < withLists; ++i)
      finestEntries += layered[i].entries.size();
    mReport = {{"clouds", describeClouds(clouds)},
               {"hash_atlas", {mLists.hashSize.x, mLists.hashSize.y}},
               {"list_entries", mLists.listEntries},
               {"list_entries_finest_level", finestEntries},
               {"records", mLists.recordCount},
               {"longest_list", mLists.longestList},
               {"dropped_entries", mLists.droppedEntries},
               {"leaf_images", leafImages.count()},
               {"lowres_atlas", {atlas.layout.width, atlas.layout.height}},
               {"parallax_margin", parallaxMargin(billboards, layered, withLists)},
               {"wood_captured", woodInImages.report}};
    setDrawLevels();
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mBillboardBuffer = device.createBuffer(MemoryCategory::kGeometry, GL_SHADER_STORAGE_BUFFER,
                                           mBillboards, "billboards");
    uploadViewOrders(device);
    // Only the instance matrices are attributes (locations 4–7, bound per level).
    mVao = gl::createVertexArray();
    const auto create = [&](int width, int height, GLenum format, const char* label) {
      gl::Texture texture = device.createTexture(
          {GL_TEXTURE_2D, width, height, 1, format, false, MemoryCategory::kTexture, label});
      return texture;
    };
    mHashTexture = create(mLists.hashSize.x, mLists.hashSize.y, GL_R32UI, "hash atlas");
    device.uploadTexture(mHashTexture, GL_RED_INTEGER, GL_UNSIGNED_INT, mLists.hash.data());
    if (mLists.wideLists) {
      mListsTexture = create(kListsWidth, mLists.listsHeight, GL_R32UI, "lists (record indices)");
      device.uploadTexture(mListsTexture, GL_RED_INTEGER, GL_UNSIGNED_INT, mLists.lists.data());
    } else {
      const std::vector<uint16_t> narrow(mLists.lists.begin(), mLists.lists.end());
      mListsTexture = create(kListsWidth, mLists.listsHeight, GL_R16UI, "lists (record indices)");
      gl::api().PixelStorei(GL_UNPACK_ALIGNMENT, 2);
      device.uploadTexture(mListsTexture, GL_RED_INTEGER, GL_UNSIGNED_SHORT, narrow.data());
      gl::api().PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    }
    mRecordTextures.clear();
    for (const RecordPlane& plane : mLists.planes) {
      gl::Texture& texture = mRecordTextures.emplace_back(
          create(kRecordsPerRow, mLists.recordsHeight, plane.internalFormat, plane.name));
      device.uploadTexture(texture, plane.format, plane.type, plane.data.data());
      gl::setTextureSampling(texture, false, false);
    }
    for (const gl::Texture* texture : {&mHashTexture, &mListsTexture})
      gl::setTextureSampling(*texture, false, false);
    mLeavesTexture = uploadAlphaTestedArray(device, mLeafLayers, true, "leaf images",
                                            parseCompression(mParams.leafImageCompression));
    mLowResTexture = uploadAlphaTestedArray(device, mLowRes, true, "low-resolution atlas",
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
    const gl::ShaderSource& fragment =
        gl::embeddedShader("methods/multilayer_indirect/multilayer_indirect.frag");
    mFragmentText =
        gl::withDefines(fragment.text, fmt::format("#define RECORDS_8BIT {}\n#define PARALLAX {}\n",
                                                   packed() ? 1 : 0, mParams.parallax ? 1 : 0));
    const gl::ShaderSource& vertex =
        gl::embeddedShader("methods/multilayer_indirect/multilayer_indirect.vert");
    mFarVertexText = gl::withDefines(vertex.text, "#define FAR_LEVEL 1\n");
    mProgram = device.createProgram({vertex, {fragment.path, mFragmentText}});
    mFarProgram =
        device.createProgram({{vertex.path, mFarVertexText},
                              gl::embeddedShader("methods/common/alpha_tested_texture.frag")});
    mLod.attach(device, device.owner() + "/frame");
    if (mParams.wood.draw) mWood.upload(device, true);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    mWood.drawAround(mParams.wood, frame, instances, [&] { drawLeaves(frame, instances); });
  }

  // Everything but the wood (drawAround orders the two).
  void drawLeaves(const FrameContext& frame, std::span<const Instance> instances) {
    const bool ordered = !mOrders.empty();
    // Each tree's walked clouds take the order of the direction nearest its view of the tree.
    mLod.update(frame, instances, mLevels.treeBounds, drawThresholds(),
                mDrawLevels.directionGrouping(mOrders, frame, kFarLevel),
                ordered ? int(mOrders.directions.size()) : 1);
    const gl::Api& g = gl::api();
    g.BindVertexArray(mVao.id());
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, mBillboardBuffer.id());
    // Unused without orders (uOrdered 0), bound so the binding never dangles.
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1,
                     ordered ? mOrdersBuffer.id() : mBillboardBuffer.id());
    const glm::vec2 lowResAtlasSize(mLowRes[0].width, mLowRes[0].height);
    mDrawLevels.draw(
        mLod,
        [&](size_t level) {
          const bool far = level >= kFarLevel;
          const gl::Program& program = far ? mFarProgram : mProgram;
          program.use();
          setFrameUniforms(program, frame);
          program.set("uOrdered", ordered && !far ? 1 : 0);
          program.set("uLowResAtlasSize", lowResAtlasSize);
          if (far) {
            program.set("uAtlas", 0);
            program.set("uBackLayer", 1.0f);
            program.set("uBinaryAlpha", mParams.compression == "dxt1" ? 1 : 0);
            program.set("uAggregateCoverage", 1);
            program.set("uOcclusion", 1);
            program.set("uHasOcclusion", mLowResOcclusionTexture.id() ? 1 : 0);
            g.ActiveTexture(GL_TEXTURE1);
            g.BindTexture(GL_TEXTURE_2D, mLowResOcclusionTexture.id());
            g.ActiveTexture(GL_TEXTURE0);
            g.BindTexture(GL_TEXTURE_2D_ARRAY, mLowResTexture.id());
          } else {
            bindLayeredTextures(program);
            program.set("uTargetPixelsPerOutputPixel", frame.targetPixelsPerOutputPixel);
            program.set("uCameraPosition", frame.cameraPosition);
          }
        },
        true,
        [&](size_t level, size_t group) {
          return ordered && level < kFarLevel
                     ? static_cast<GLint>(6 * mOrders.firstSlot(int(group), level))
                     : static_cast<GLint>(mDrawLevels.ranges[level].first);
        });
    g.ActiveTexture(GL_TEXTURE0);
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
    g.BindVertexArray(0);
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
    asset.writeFields(AssetFields{mLists.hashSize, mLists.listsHeight, mLists.wideLists,
                                  mLists.listEntries, mLists.recordCount, mLists.recordsHeight,
                                  mLists.axisScale, mLists.heightScale, mLeafLayers.size() / 2,
                                  mLowRes.size() > 1, !mLowResOcclusion.empty()});
    // What the GPU holds is what is stored: 16-bit list entries where they fit, 8-bit records.
    if (mLists.wideLists) {
      asset.writeBlob("lists.bin", mLists.lists);
    } else {
      asset.writeBlob("lists.bin", std::vector<uint16_t>(mLists.lists.begin(), mLists.lists.end()));
    }
    for (const RecordPlane& plane : mLists.planes)
      asset.writeBlob(std::string(plane.name) + ".bin", plane.data);
    asset.writeBlob("billboards.bin", mBillboards);
    asset.writeBlob("hash.bin", mLists.hash);
    asset.writeImages("leaf_image_{}.png", mLeafLayers);
    asset.writeImages("lowres_{}.png", mLowRes);
    if (!mLowResOcclusion.empty()) asset.writeImage("lowres_occlusion.png", mLowResOcclusion);
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("multilayer_indirect");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    ListTextures& l = mLists;
    l = {};
    l.eightBit = packed();
    l.hashSize = fields.hashSize;
    l.listsHeight = fields.listsHeight;
    l.wideLists = fields.wideLists;
    l.listEntries = fields.listEntries;
    l.recordCount = fields.records;
    l.recordsHeight = fields.recordsHeight;
    l.axisScale = fields.axisScale;
    l.heightScale = fields.heightScale;
    mBillboards = asset.readBlobAs<BillboardRecord>("billboards.bin");
    l.hash = asset.readBlobAs<uint32_t>("hash.bin");
    if (l.wideLists) {
      l.lists = asset.readBlobAs<uint32_t>("lists.bin");
    } else {
      const auto narrow = asset.readBlobAs<uint16_t>("lists.bin");
      l.lists.assign(narrow.begin(), narrow.end());
    }
    l.planes = emptyRecordPlanes(packed(), std::max(l.recordsHeight, 0));
    bool sizesMatch = true;
    for (RecordPlane& plane : l.planes) {
      const size_t expected = plane.data.size();
      plane.data = asset.readBlobAs<uint8_t>(std::string(plane.name) + ".bin");
      sizesMatch = sizesMatch && plane.data.size() == expected;
    }
    mLeafLayers = asset.readImages("leaf_image_{}.png", fields.leafImages * 2);
    mLowRes = asset.readImages("lowres_{}.png", fields.lowResBack ? 2 : 1);
    mLowResOcclusion =
        fields.lowResOcclusion ? asset.readImage("lowres_occlusion.png") : ImageRgba8();
    if (!sizesMatch || l.hashSize.x < 1 || l.hashSize.y < 1 || l.listsHeight < 1 ||
        l.recordsHeight < 1 || l.recordCount > size_t(kRecordsPerRow) * l.recordsHeight ||
        l.hash.size() != size_t(l.hashSize.x) * l.hashSize.y ||
        l.lists.size() != size_t(kListsWidth) * l.listsHeight || l.listEntries > l.lists.size()) {
      throwInputError("{}: hash, lists or records blob has the wrong size", folder);
    }
    validateLoaded(folder);
    mLevels.load(asset, mBillboards.size() * 6);
    setDrawLevels();
    mWood.load(asset);
    asset.finishReading();
  }

 private:
  bool packed() const { return mParams.listsPrecision == "8bit"; }
  bool middleLowRes() const { return mParams.lodLowResPixels > 0.0f; }

  // The instance LoD thresholds (output pixels): the clouds' own, with lod_lowres_px between.
  std::vector<float> drawThresholds() const {
    std::vector<float> thresholds = mParams.cloud.thresholds();
    if (middleLowRes()) thresholds.insert(thresholds.begin() + 1, mParams.lodLowResPixels);
    return thresholds;
  }
  // The largest projected radii the clouds drawn as low-resolution textures only are drawn at,
  // finest first: the middle cloud below lod_lowres_px (when set), the far one below lod_far_px.
  std::vector<float> lowResOnlyThresholds() const {
    if (!mParams.cloud.lod) return {};
    if (middleLowRes()) return {mParams.lodLowResPixels, mParams.cloud.lodFarPixels};
    return {mParams.cloud.lodFarPixels};
  }
  // Levels from kFarLevel on draw the low-resolution texture only: with lod_lowres_px the middle
  // cloud's range is drawn a second time there, before the far cloud's.
  void setDrawLevels() {
    mDrawLevels = mLevels;
    if (middleLowRes() && mLevels.ranges.size() > kFarLevel)
      mDrawLevels.ranges.insert(mDrawLevels.ranges.begin() + kFarLevel, mLevels.ranges[1]);
  }

  // The largest growth of a layered billboard's rectangle for parallax (0 without), in units of
  // the billboards' mean half extent, for the report.
  static float parallaxMargin(const std::vector<const Billboard*>& billboards,
                              const std::vector<LayeredBillboard>& layered, size_t withLists) {
    float margin = 0.0f;
    for (size_t i = 0; i < withLists; ++i) {
      const glm::vec2 grown = layered[i].halfExtents - billboards[i]->halfExtents;
      margin = std::max({margin, grown.x, grown.y});
    }
    return margin;
  }

  // A load checks every index the shader follows: hash cells into the lists, list entries into
  // their billboard's records, records into the leaf images.
  void validateLoaded(const std::string& folder) const {
    const ListTextures& l = mLists;
    for (uint32_t word : l.hash) {
      if (word != 0 && size_t(word >> 8) + (word & 255u) > l.listEntries)
        throwInputError("{}: hash cell points past the lists", folder);
    }
    for (size_t e = 0; e < l.listEntries; ++e) {
      if (l.lists[e] >= l.recordCount)
        throwInputError("{}: list entry names a missing leaf record", folder);
    }
    const auto inside = [](glm::ivec2 origin, glm::ivec2 size, glm::ivec2 bounds) {
      return origin.x + size.x <= bounds.x && origin.y + size.y <= bounds.y;
    };
    for (const BillboardRecord& b : mBillboards) {
      if (b.recordBase > l.recordCount)
        throwInputError("{}: billboard names a missing leaf record", folder);
      if (!inside(unpackPair(b.hashOrigin), unpackPair(b.hashCells), l.hashSize))
        throwInputError("{}: billboard's hash cells lie outside the hash atlas", folder);
      if (!inside(unpackPair(b.lowResOrigin), unpackPair(b.lowResSize),
                  {mLowRes[0].width, mLowRes[0].height}))
        throwInputError("{}: billboard's low-resolution rectangle lies outside the atlas", folder);
      if (!std::isfinite(b.center.x + b.center.y + b.center.z + b.halfExtents.x + b.halfExtents.y))
        throwInputError("{}: billboard with a non-finite centre or extent", folder);
    }
    for (size_t r = 0; r < l.recordCount; ++r) {
      if (decodeRecord(l, r, glm::vec2(1.0f)).image >= mLeafLayers.size() / 2)
        throwInputError("{}: leaf record names a missing leaf image", folder);
    }
    if (mLowRes.size() == 2 &&
        (mLowRes[1].width != mLowRes[0].width || mLowRes[1].height != mLowRes[0].height))
      throwInputError("{}: lowres_1.png is not the size of lowres_0.png", folder);
  }

  static ImageRgba8 quarterResolution(const ImageRgba8& full) {
    constexpr int kFactor = 4;
    ImageRgba8 out(std::max(1, (full.width + kFactor - 1) / kFactor),
                   std::max(1, (full.height + kFactor - 1) / kFactor));
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) {
        int sum = 0, count = 0;
        for (int dy = 0; dy < kFactor; ++dy)
          for (int dx = 0; dx < kFactor; ++dx) {
            const int sx = kFactor * x + dx, sy = kFactor * y + dy;
            if (sx >= full.width || sy >= full.height) continue;
            sum += full.at(sx, sy)[0];
            ++count;
          }
        uint8_t* texel = out.at(x, y);
        texel[0] = texel[1] = texel[2] = uint8_t((sum + count / 2) / std::max(count, 1));
        texel[3] = 255;
      }
    return out;
  }

  void makeBillboardRecords(const std::vector<const Billboard*>& billboards,
                            const std::vector<LayeredBillboard>& layered, const ImageAtlas& atlas) {
    mBillboards.clear();
    const auto fits = [](glm::ivec2 v) {
      return v.x >= 0 && v.y >= 0 && v.x <= 65535 && v.y <= 65535;
    };
    if (!fits({atlas.layout.width, atlas.layout.height}))
      throwInputError(
          "multilayer_indirect: the low-resolution atlas outgrows 65535 texels; lower "
          "'lowres_texels_per_cell' or 'hash_resolution'");
    for (size_t i = 0; i < billboards.size(); ++i) {
      const Billboard& b = *billboards[i];
      if (!fits(mLists.hashOrigins[i]) || !fits(layered[i].cells))
        throwInputError(
            "multilayer_indirect: the hash atlas outgrows 65535 cells; lower 'hash_resolution'");
      mBillboards.push_back({b.center, packSnorm10(b.normal), layered[i].halfExtents,
                             packSnorm10(b.axisU), static_cast<uint32_t>(mLists.recordBase[i]),
                             packPair(mLists.hashOrigins[i]), packPair(layered[i].cells),
                             packPair(atlas.layout.origins[i]), packPair(atlas.sizes[i])});
    }
  }

  // view_orders: the walked clouds' billboards sorted per view direction, 16-bit indices two to
  // a word (multilayer_indirect.vert).
  void uploadViewOrders(gl::Device& device) {
    mOrders = {};
    mOrdersBuffer = {};
    if (mParams.viewOrders == 0) return;
    if (mBillboards.size() > 65535)
      throwInputError(
          "multilayer_indirect: parameter 'view_orders' needs at most 65,535 billboards ({}); "
          "set it to 0 or lower 'clusters'",
          mBillboards.size());
    std::vector<glm::vec3> centers;
    for (const BillboardRecord& b : mBillboards) centers.push_back(b.center);
    mOrders = mLevels.viewOrders(centers, kFarLevel, mParams.viewOrders);
    std::vector<uint32_t> words((mOrders.order.size() + 1) / 2, 0u);
    for (size_t i = 0; i < mOrders.order.size(); ++i)
      words[i / 2] |= mOrders.order[i] << (16 * (i % 2));
    mOrdersBuffer = device.createBuffer(gl::MemoryCategory::kGeometry, GL_SHADER_STORAGE_BUFFER,
                                        words, "view orders");
  }

  void bindLayeredTextures(const gl::Program& program) const {
    const gl::Api& g = gl::api();
    program.set("uHash", 0);
    program.set("uLists", 1);
    program.set("uLeaves", 2);
    program.set("uLowRes", 3);
    program.set("uLowResOcclusion", 4);
    program.set("uHasLowResOcclusion", mLowResOcclusionTexture.id() ? 1 : 0);
    program.set("uLodFactor", mParams.lodFactor);
    program.set("uLowResRestOnly", mParams.lowResFallback == "rest" ? 1 : 0);
    program.set("uLowResBinaryAlpha", mParams.compression == "dxt1" ? 1 : 0);
    program.set("uLeavesBinaryAlpha", mParams.leafImageCompression == "dxt1" ? 1 : 0);
    program.set("uAxisScale", mLists.axisScale);
    program.set("uHeightScale", mLists.heightScale);
    program.set("uMaxSlope", std::tan(mParams.parallaxMaxAngle * kPi / 180.0f));
    std::vector<std::pair<GLenum, GLuint>> units = {{GL_TEXTURE_2D, mHashTexture.id()},
                                                    {GL_TEXTURE_2D, mListsTexture.id()},
                                                    {GL_TEXTURE_2D_ARRAY, mLeavesTexture.id()},
                                                    {GL_TEXTURE_2D_ARRAY, mLowResTexture.id()},
                                                    {GL_TEXTURE_2D, mLowResOcclusionTexture.id()}};
    // The record planes (list_textures.h), ambient occlusion last, from unit 5 on.
    static constexpr const char* kPlaneUniforms[] = {"uRecordsA", "uRecordsB", "uRecordsC"};
    for (size_t p = 0; p < mRecordTextures.size(); ++p) {
      const bool last = p + 1 == mRecordTextures.size();
      program.set(last ? "uAmbientOcclusion" : kPlaneUniforms[p], static_cast<int>(units.size()));
      units.emplace_back(GL_TEXTURE_2D, mRecordTextures[p].id());
    }
    for (GLenum unit = 0; unit < units.size(); ++unit) {
      g.ActiveTexture(GL_TEXTURE0 + unit);
      g.BindTexture(units[unit].first, units[unit].second);
    }
  }

  MultilayerParams mParams;
  nlohmann::json mReport;
  CloudLevels mLevels;      // as baked: the near, middle and far clouds
  CloudLevels mDrawLevels;  // as drawn: the middle cloud twice with lod_lowres_px (setDrawLevels)
  std::vector<BillboardRecord> mBillboards;
  ListTextures mLists;
  std::vector<ImageRgba8> mLeafLayers;  // leaf image i: front 2i, back 2i + 1
  std::vector<ImageRgba8> mLowRes;      // the low-resolution atlas seen from the front, the back
  ImageRgba8 mLowResOcclusion;          // AO of the low-resolution atlas at a quarter (R)
  std::string mFragmentText;            // the fragment shader with its variant's defines
  std::string mFarVertexText;           // the vertex shader for the far level
  gl::Buffer mBillboardBuffer;          // mBillboards, pulled by the vertex shader
  ViewOrders mOrders;                   // view_orders: empty without
  gl::Buffer mOrdersBuffer;             // mOrders.order, 16-bit, two to a word
  gl::VertexArray mVao;
  gl::Texture mHashTexture, mListsTexture, mLeavesTexture, mLowResTexture, mLowResOcclusionTexture;
  std::vector<gl::Texture> mRecordTextures;  // one per record plane, ambient occlusion last
  gl::Program mProgram, mFarProgram;
  LodInstances mLod;
  WoodRenderer mWood;
};

}  // namespace

void registerMultilayerIndirect(MethodRegistry& registry) {
  addMethod<MultilayerIndirect, MultilayerParams>(
      registry, "multilayer_indirect",
      "multi-layer indirect texturing (García et al. 2007): lists of leaf fragments per hash cell",
      {.memoryKnob = MemoryKnob{"hash_resolution", 16, 1024, true, true},
       .cost = {.bakeSeconds = 1.2, .frameCost = 1.0}});
}

}  // namespace canopy
