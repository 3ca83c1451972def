#include "methods/billboard_cloud/billboard_cloud.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <utility>

#include <glm/geometric.hpp>

#include "common/config.h"
#include "methods/common/billboard_cloud.h"
#include "methods/common/cloud_levels.h"
#include "methods/common/cloud_params.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/common/wood_capture.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct BillboardCloudParams {
  CloudParams cloud;
  float density = 16.0f;
  int supersample = 4;
  int maxBillboardTexels = 1024;
  bool mipmaps = true;
  WoodParams wood;
  std::string compression = "none";
  bool backCapture = true;
  float woodCapturePixels = 3.0f;
  // 0: the far cloud holds what both coarse clouds hold. 16 px (the default of 873fbdf) drew the
  // 1,000-tree forest 15% faster but scattered the bare branches of far sparse trees into
  // brown blobs: 22 radii 16.1 against 18.7 dB (docs/METHODS.md, "the far cloud's own bound").
  float woodCaptureFarPixels = 0.0f;
  bool woodCaptureParts = false;
  std::string alphaTest = "hashed";

  template <class Visitor>
  void visit(Visitor& v) {
    cloud.visit(v);
    v("density", density, 0.01f, 100000.0f,
      "texels per unit length of billboard side, in the tree's own units (a tree modelled in "
      "centimetres needs a hundredth of a metre tree's density; the memory knob)");
    v("supersample", supersample, 1, 8, "capture samples per texel side");
    v("max_billboard_texels", maxBillboardTexels, 1, 8192, "cap on one billboard's texture side");
    v("mipmaps", mipmaps, "mipmapped atlas (trilinear, coverage-preserving levels)");
    wood.visit(v);
    v("compression", compression, {"none", "dxt1", "dxt5"},
      "the atlas: uncompressed, BC1 or BC3 (S3TC)");
    v("back_capture", backCapture,
      "a second atlas layer captured from each billboard's back side (false: seen from behind, "
      "a billboard shows its front capture mirrored, as the classic method does)");
    v("wood_capture_px", woodCapturePixels, 0.0f, 100.0f,
      "the middle and far clouds' images also hold the wood lying (every corner) within this "
      "many output pixels of one of their billboards, measured at the largest projected size "
      "each cloud is drawn at; trees drawn with them draw only the rest of the wood as geometry "
      "(0: images of leaves only; 0 in effect without lod or wood)");
    v("wood_capture_far_px", woodCaptureFarPixels, 0.0f, 100.0f,
      "the far cloud's own bound instead (0: wood_capture_px's): its images hold the wood within "
      "this many output pixels of its billboards at its largest projected size (lod_far_px), "
      "and trees drawn with it draw only the rest; the middle cloud keeps what wood_capture_px "
      "gives both clouds (at least wood_capture_px; 0 in effect without lod or wood)");
    v("wood_capture_parts", woodCaptureParts,
      "capture the wood a connected part at a time (a branch segment's tube): whole into the "
      "nearest billboard that holds all of it within the bound, or not at all (false: each "
      "triangle on its own, into the billboard it faces most squarely)");
    v("alpha_test", alphaTest, {"fixed", "hashed"},
      "the atlas' alpha test: at 0.5 everywhere, as the reference tests its leaf cards; or, "
      "where the atlas is minified (its mip levels average several texels), against a threshold "
      "hashed per pixel and primitive that keeps the averaged coverage in expectation (0.5 where "
      "magnified)");
  }
};

constexpr int kAtlasPadding = 4;
constexpr int kAtlasAlignment = 8;

class BillboardCloudMethod final : public Method {
 public:
  explicit BillboardCloudMethod(BillboardCloudParams params) : mParams(std::move(params)) {
    mParams.cloud.resolve("billboard_cloud");
    // Without coarse clouds there are no images to hold wood, and without wood nothing to
    // hold: the effective parameters say that no wood is captured.
    resolveWoodCapture("billboard_cloud", mParams.cloud.lod, mParams.wood.draw,
                       mParams.woodCapturePixels, mParams.woodCaptureFarPixels);
    if (mParams.woodCapturePixels <= 0.0f && mParams.woodCaptureFarPixels <= 0.0f)
      mParams.woodCaptureParts = false;
  }

  void bake(const Tree& tree, BakeContext& ctx) override {
    mLevels = {};
    mLevels.treeBounds = tree.bounds;
    const std::vector<BillboardCloud> clouds =
        buildBillboardCloudFamily(tree, mParams.cloud.levels(), ctx.seed);
    mReport = {{"clouds", describeClouds(clouds)}};
    // Texture size of every billboard at the requested density.
    std::vector<const Billboard*> billboards;
    std::vector<glm::ivec2> sizes;
    for (const BillboardCloud& cloud : clouds) {
      mLevels.addLevel(billboards.size(), cloud.billboards.size());
      for (const Billboard& billboard : cloud.billboards) {
        billboards.push_back(&billboard);
        const auto texels = [&](float halfExtent) {
          return std::clamp(static_cast<int>(std::ceil(2.0f * halfExtent * mParams.density)), 1,
                            mParams.maxBillboardTexels);
        };
        sizes.emplace_back(texels(billboard.halfExtents.x), texels(billboard.halfExtents.y));
      }
    }
    // The middle and far clouds' images hold the wood trees drawn with them do not draw.
    const WoodInImages woodInImages = captureWoodInImages(
        tree, clouds, 1, {mParams.cloud.lodNearPixels, mParams.cloud.lodFarPixels},
        mParams.woodCapturePixels, mParams.woodCaptureFarPixels, mParams.woodCaptureParts);
    mReport["wood_captured"] = woodInImages.report;
    mWood.bake(tree, mParams.wood.levels(), woodInImages.captured);
    const AtlasLayout preview = packAtlas(sizes, kAtlasPadding, kAtlasAlignment);
    if (preview.width > kMaxAtlas || preview.height > kMaxAtlas) {
      throwInputError(
          "billboard_cloud: parameter 'density' = {} needs a {}x{} atlas, above {}; lower it",
          mParams.density, preview.width, preview.height, kMaxAtlas);
    }
    const LeafImageSampler sampler(tree);
    const WoodColorSampler woodColors(tree);
    const TwoSidedAtlas captured = captureTwoSidedAtlas(
        tree, sampler, billboards, sizes, mParams.supersample, mParams.backCapture, kAtlasPadding,
        kAtlasAlignment, &woodColors, &woodInImages.perBillboard);
    const ImageAtlas& atlas = captured.front;
    // Both sides share one layout: the back capture is the atlas' second layer.
    mAtlas = {atlas.image};
    if (mParams.backCapture) mAtlas.push_back(captured.back);
    mVertices.clear();
    mIndices.clear();
    for (size_t i = 0; i < billboards.size(); ++i) {
      const auto base = static_cast<uint32_t>(mVertices.size());
      for (int c = 0; c < 4; ++c)
        mVertices.push_back(
            {billboards[i]->corner(c), billboards[i]->normal, atlas.cornerUv(i, c)});
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
    }
    const AtlasLayout& layout = atlas.layout;
    mReport["atlas"] = {layout.width, layout.height};
    reportTexelsPerRadius(tree, layout);
  }

  // `density` is in the tree's own units, so a tree modelled in other units than the presets'
  // metres gets an atlas far from what the defaults were measured at (docs/METHODS.md: a 75-unit
  // radius asset took 1.3 GB at 16 texels a unit). The texels per bounding radius go in the
  // report, and a bake far above the measured ones (40 to 120 on the presets) says which key to
  // set. Below them the atlas is only coarser; the memory knob covers that.
  void reportTexelsPerRadius(const Tree& tree, const AtlasLayout& layout) {
    const float radius = tree.boundingSphereRadius();
    const float texelsPerRadius = mParams.density * radius;
    mReport["texels_per_bounding_radius"] = texelsPerRadius;
    if (texelsPerRadius <= kMeasuredTexelsPerRadius * kUnitMismatchFactor) return;
    spdlog::warn(
        "billboard_cloud: parameter 'density' = {} texels a unit gives {:.0f} texels per bounding "
        "radius ({:.3g} units) and a {}x{} atlas; the defaults were measured at about {:.0f} "
        "(density {:.3g} for this tree)",
        mParams.density, texelsPerRadius, radius, layout.width, layout.height,
        kMeasuredTexelsPerRadius, kMeasuredTexelsPerRadius / radius);
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices,
                               "billboard vertices");
    mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mIndices,
                               "billboard indices");
    mAtlasTexture = uploadAlphaTestedArray(device, mAtlas, mParams.mipmaps, "billboard atlas",
                                           parseCompression(mParams.compression));
    mVao = makeMeshVertexArray(mVbo, mIbo);
    mProgram =
        device.createProgram({gl::embeddedShader("methods/common/mesh.vert"),
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
    mLod.update(frame, instances, mLevels.treeBounds, mParams.cloud.thresholds());
    const gl::Api& g = gl::api();
    mProgram.use();
    setFrameUniforms(mProgram, frame);
    mProgram.set("uAtlas", 0);
    mProgram.set("uBackLayer", float(mAtlas.size() - 1));
    mProgram.set("uBinaryAlpha", mParams.compression == "dxt1" ? 1 : 0);
    mProgram.set("uAggregateCoverage", mParams.alphaTest == "hashed" ? 2 : 0);
    // The lit variant declares the occlusion sampler too: a unit of its own (a 2D and an array
    // sampler on one unit is an invalid draw), unused as uHasOcclusion is 0.
    mProgram.set("uOcclusion", 1);
    mProgram.set("uHasOcclusion", 0);
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D_ARRAY, mAtlasTexture.id());
    g.BindVertexArray(mVao.id());
    mLevels.draw(mLod, {});
    g.BindVertexArray(0);
  }

  uint64_t lodSignature() const override {
    return fnv1aMix(mLod.signature(), mWood.lodSignature());
  }
  std::vector<uint64_t> woodInstancesPerLevel() const override { return mWood.instancesPerLevel(); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mWood.withLevels(mReport); }

  void save(AssetFolder& asset) const override {
    asset.describe("billboard_cloud", effectiveParams(), mReport);
    mLevels.save(asset);
    asset.writeBlob("vertices.bin", mVertices);
    asset.writeBlob("indices.bin", mIndices);
    asset.writeImage("atlas.png", mAtlas[0]);
    if (mAtlas.size() > 1) asset.writeImage("atlas_back.png", mAtlas[1]);
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("billboard_cloud");
    mVertices = asset.readBlobAs<MeshVertex>("vertices.bin");
    mIndices = asset.readBlobAs<uint32_t>("indices.bin");
    mAtlas = {asset.readImage("atlas.png")};
    if (mParams.backCapture) {
      mAtlas.push_back(asset.readImage("atlas_back.png"));
      if (mAtlas[1].width != mAtlas[0].width || mAtlas[1].height != mAtlas[0].height)
        throwInputError("{}: atlas_back.png is not the size of atlas.png", asset.folder().string());
    }
    mWood.load(asset);
    validateIndices(mIndices, mVertices.size(), asset.folder().string());
    mLevels.load(asset, mIndices.size());
    asset.finishReading();
  }

 private:
  static constexpr int kMaxAtlas = 16384;
  // Texels per bounding radius of broadleaf at the default density, and how far above it a bake
  // is warned about.
  static constexpr float kMeasuredTexelsPerRadius = 120.0f;
  static constexpr float kUnitMismatchFactor = 4.0f;
  BillboardCloudParams mParams;
  nlohmann::json mReport;
  CloudLevels mLevels;
  std::vector<MeshVertex> mVertices;
  std::vector<uint32_t> mIndices;
  std::vector<ImageRgba8> mAtlas;  // the front capture, then the back capture if any
  gl::Buffer mVbo, mIbo;
  gl::VertexArray mVao;
  gl::Texture mAtlasTexture;
  gl::Program mProgram;
  LodInstances mLod;
  WoodRenderer mWood;
};

}  // namespace

void registerBillboardCloud(MethodRegistry& registry) {
  addMethod<BillboardCloudMethod, BillboardCloudParams>(
      registry, "billboard_cloud",
      "classic billboard cloud: one orthographic leaf texture per billboard",
      {.memoryKnob = MemoryKnob{"density", 2, 512, false, true},
       .cost = {.bakeSeconds = 1.2, .frameCost = 0.7}});
}

}  // namespace canopy
