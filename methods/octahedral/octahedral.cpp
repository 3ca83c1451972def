#include "methods/octahedral/octahedral.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "common/config.h"
#include "methods/common/dxt.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/octahedral/mesh_fade.h"
#include "methods/octahedral/octahedral_capture.h"
#include "methods/octahedral/octahedral_mapping.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct OctahedralParams {
  int frames = 16;
  bool hemisphere = true;
  int atlasSize = 2048;
  int normalDepthDivisor = 2;
  int supersample = 2;
  int padding = 4;
  std::string blend = "three";
  int parallaxSteps = 2;
  bool mipmaps = true;
  std::string compression = "dxt5";
  bool wood = true;
  float meshPixels = 0.0f;
  float fadeBand = 0.25f;

  template <class Visitor>
  void visit(Visitor& v) {
    v("frames", frames, 2, 64, "N: the atlas holds N × N frames (Unreal's ImpostorBaker: 16)");
    v("hemisphere", hemisphere,
      "frames on the upper hemisphere only (views from below use the horizon's)");
    v("atlas_size", atlasSize, 64, 8192,
      "colour atlas texels per side; each frame gets atlas_size / N (the memory knob)");
    v("normal_depth_divisor", normalDepthDivisor, 1, 4,
      "1, 2 or 4: the normal-depth atlas has atlas_size / divisor texels per side");
    v("supersample", supersample, 1, 8, "capture rays per texel side (coverage and colour)");
    v("padding", padding, 1, 16, "transparent texels around each frame, so filtering stays inside");
    v("blend", blend, {"three", "nearest"},
      "three frames around the view blended by barycentric weight, or the nearest frame alone");
    v("parallax_steps", parallaxSteps, 0, 8,
      "depth reprojection steps per frame lookup (0: each frame read at the quad point)");
    v("mipmaps", mipmaps, "mipmapped atlases (coverage-preserving colour levels)");
    v("compression", compression, {"none", "dxt5"},
      "both atlases uncompressed or BC3 (S3TC): colour sRGB, normal-depth linear");
    v("wood", wood, "capture the trunk and branches into the frames (false: leaves only)");
    v("mesh_pixels", meshPixels, 0.0f, 100000.0f,
      "an instance whose bounding radius spans this many output pixels is drawn as the polygonal "
      "mesh (0: never; the mesh then costs no memory)");
    v("fade_band", fadeBand, 0.01f, 1.0f,
      "the dithered cross-fade to the mesh starts at mesh_pixels · (1 − fade_band)");
  }
};

// The asset header's own part: what the draw needs besides the atlases.
struct AssetFields {
  int cellTexels = 0;
  glm::vec3 center{0.0f};
  float radius = 0.0f;
  template <class V>
  void visit(V& v) {
    v("cell_texels", cellTexels);
    v("center", center);
    v("radius", radius);
  }
};

constexpr GLenum kLinearDxt5 = 0x83F3;  // GL_COMPRESSED_RGBA_S3TC_DXT5_EXT

class OctahedralMethod final : public Method {
 public:
  explicit OctahedralMethod(OctahedralParams params)
      : mParams(std::move(params)), mMesh(mParams.meshPixels, mParams.fadeBand) {
    mCellTexels = cellTexels(mParams);
  }

  void bake(const Tree& tree, BakeContext& ctx) override {
    OctahedralCaptureSettings settings;
    settings.grid = grid();
    settings.cellTexels = mCellTexels;
    settings.padding = mParams.padding;
    settings.supersample = mParams.supersample;
    settings.wood = mParams.wood;
    OctahedralFrames frames = captureOctahedralFrames(tree, settings);
    mColor = std::move(frames.color);
    mNormalDepth = std::move(frames.normalDepth);
    for (int d = mParams.normalDepthDivisor; d > 1; d /= 2) mNormalDepth = halveImage(mNormalDepth);
    mCenter = frames.center;
    mRadius = frames.radius;
    mMesh.bake(tree, ctx);
    mReport = {{"frames", mParams.frames * mParams.frames},
               {"frame_texels", mCellTexels - 2 * mParams.padding},
               {"atlas", {mColor.width, mColor.height}},
               {"normal_depth_atlas", {mNormalDepth.width, mNormalDepth.height}},
               {"covered_fraction", frames.coveredFraction}};
  }

  void upload(gl::Device& device) override {
    const Compression compression = parseCompression(mParams.compression);
    mColorTexture =
        uploadAlphaTestedTexture(device, mColor, mParams.mipmaps, "octahedral colour", compression);
    mNormalDepthTexture = uploadLinearTexture(device, mNormalDepth, compression);
    mVao = gl::createVertexArray();
    gl::api().BindVertexArray(0);
    mProgram = device.createProgram({gl::embeddedShader("methods/octahedral/octahedral.vert"),
                                     gl::embeddedShader("methods/octahedral/octahedral.frag")});
    mMesh.upload(device, device.owner() + "/frame");
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    // Near instances are the mesh (or fade into it); the impostor draws the rest.
    std::vector<MeshCrossFade::ImpostorDraw> draws{
        {0, static_cast<GLsizei>(instances.size()), {0.0f, 1.0f}}};
    GLuint instanceBuffer = frame.instanceBuffer;
    const std::vector<MeshCrossFade::State>* states = nullptr;
    if (mMesh.enabled()) {
      states = &mMesh.drawMeshSide(frame, instances, mCenter, mRadius);
      draws = mMesh.impostorDraws();
      instanceBuffer = mMesh.impostorBuffer();
    }
    updateSignature(frame, instances, states);
    const gl::Api& g = gl::api();
    mProgram.use();
    setFrameUniforms(mProgram, frame);
    const glm::mat4 cameraToWorld = glm::inverse(frame.view);
    const bool orthographic = frame.projection[3][3] == 1.0f;
    mProgram.set("uEye", glm::vec3(cameraToWorld[3]));
    mProgram.set("uForward", -glm::normalize(glm::vec3(cameraToWorld[2])));
    mProgram.set("uOrthographic", orthographic ? 1 : 0);
    mProgram.set("uViewer", frame.cameraPosition);
    mProgram.set("uLodFocalPixels", frame.lodFocalPixels);
    const int inner = mCellTexels - 2 * mParams.padding;
    // Levels past log2(padding) + 1 would mix neighbouring frames.
    mProgram.set("uMaxLod", mParams.mipmaps ? std::log2(float(mParams.padding)) + 1.0f : 0.0f);
    mProgram.set("uCenter", mCenter);
    mProgram.set("uRadius", mRadius);
    mProgram.set("uFrames", mParams.frames);
    mProgram.set("uHemisphere", mParams.hemisphere ? 1 : 0);
    mProgram.set("uBlendFrames", mParams.blend == "three" ? 3 : 1);
    mProgram.set("uInnerTexels", float(inner));
    const float atlas = float(mCellTexels * mParams.frames);
    mProgram.set("uCellUv", float(mCellTexels) / atlas);
    mProgram.set("uPaddingUv", float(mParams.padding) / atlas);
    mProgram.set("uInnerUv", float(inner) / atlas);
    mProgram.set("uParallaxSteps", mParams.parallaxSteps);
    mProgram.set("uNormalDepthLodOffset", std::log2(float(mParams.normalDepthDivisor)));
    mProgram.set("uColor", 0);
    mProgram.set("uNormalDepth", 1);
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D, mColorTexture.id());
    g.ActiveTexture(GL_TEXTURE1);
    g.BindTexture(GL_TEXTURE_2D, mNormalDepthTexture.id());
    g.BindVertexArray(mVao.id());
    for (const MeshCrossFade::ImpostorDraw& draw : draws) {
      mProgram.set("uDitherKeep", draw.ditherKeep);
      bindInstanceMatrices(instanceBuffer, 4, draw.first);
      g.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, draw.count);
    }
    g.BindVertexArray(0);
    g.ActiveTexture(GL_TEXTURE1);
    g.BindTexture(GL_TEXTURE_2D, 0);
    g.ActiveTexture(GL_TEXTURE0);
  }

  uint64_t lodSignature() const override { return mSignature; }
  uint64_t leafPolygonsDrawn() const override { return mMesh.leafPolygonsDrawn(); }
  std::vector<uint64_t> instancesPerLevel() const override {
    return mMesh.enabled() ? mMesh.instancesPerState() : std::vector<uint64_t>{};
  }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mReport; }

  void save(AssetFolder& asset) const override {
    asset.describe("octahedral", effectiveParams(), mReport);
    asset.writeFields(AssetFields{mCellTexels, mCenter, mRadius});
    asset.writeImage("color.png", mColor);
    asset.writeImage("normal_depth.png", mNormalDepth);
    mMesh.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("octahedral");
    AssetFields fields;
    asset.readFields(fields);
    mColor = asset.readImage("color.png");
    mNormalDepth = asset.readImage("normal_depth.png");
    asset.finishReading();
    mMesh.load(asset);
    const int side = mCellTexels * mParams.frames;
    if (fields.cellTexels != mCellTexels || mColor.width != side || mColor.height != side ||
        mNormalDepth.width != side / mParams.normalDepthDivisor ||
        mNormalDepth.height != side / mParams.normalDepthDivisor || !(fields.radius > 0.0f) ||
        !std::isfinite(fields.radius))
      throwInputError("{}: corrupt octahedral asset (atlas sizes or sphere do not match)",
                      asset.folder().string());
    mCenter = fields.center;
    mRadius = fields.radius;
  }

 private:
  OctahedralGrid grid() const { return {mParams.frames, mParams.hemisphere}; }

  // A frame's cell: the largest size within atlas_size / N that keeps every cell a whole number
  // of 4×4 blocks in both atlases (the normal-depth one divided).
  static int cellTexels(const OctahedralParams& params) {
    if (params.normalDepthDivisor == 3)
      throwInputError("octahedral: parameter 'normal_depth_divisor' = 3: use 1, 2 or 4");
    const int quantum = 4 * params.normalDepthDivisor;
    const int cell = params.atlasSize / params.frames / quantum * quantum;
    if (cell - 2 * params.padding < 8)
      throwInputError(
          "octahedral: parameter 'atlas_size' = {} leaves {} texels per frame for {} frames "
          "(padding {}): at least 8 are needed; raise atlas_size or lower frames",
          params.atlasSize, cell - 2 * params.padding, params.frames * params.frames,
          params.padding);
    return cell;
  }

  gl::Texture uploadLinearTexture(gl::Device& device, const ImageRgba8& image,
                                  Compression compression) const {
    requireS3tcFor(compression);
    const bool compressed = compression != Compression::kNone;
    gl::Texture texture = device.createTexture(
        {GL_TEXTURE_2D, image.width, image.height, 1, compressed ? kLinearDxt5 : GLenum(GL_RGBA8),
         mParams.mipmaps, gl::MemoryCategory::kTexture, "octahedral normal-depth"});
    ImageRgba8 level = image;
    for (int l = 0; l < texture.levels; ++l) {
      if (l > 0) level = halveImage(level);
      if (compressed)
        device.uploadCompressedLevel(texture, l, 0, compressImage(level, compression));
      else
        device.uploadTextureLevel(texture, l, GL_RGBA, GL_UNSIGNED_BYTE, level.pixels.data());
    }
    gl::setTextureSampling(texture, true, false);
    return texture;
  }

  // The frame triple each instance shows from the viewer and whether it is the mesh, fading or
  // the impostor: the popping metric's marks.
  void updateSignature(const FrameContext& frame, std::span<const Instance> instances,
                       const std::vector<MeshCrossFade::State>* states) {
    uint64_t hash = 0xcbf29ce484222325ull;
    const OctahedralGrid octahedralGrid = grid();
    for (size_t i = 0; i < instances.size(); ++i) {
      const Instance& instance = instances[i];
      if (states) hash = fnv1aMix(hash, static_cast<uint64_t>((*states)[i]));
      const glm::mat4 toLocal = glm::inverse(instance.modelMatrix());
      const glm::vec3 eye = glm::vec3(toLocal * glm::vec4(frame.cameraPosition, 1.0f));
      const glm::vec3 offset = eye - mCenter;
      if (glm::length(offset) < 1e-6f) continue;
      const FrameBlend blend = blendFrames(octahedralGrid, glm::normalize(offset));
      for (const glm::ivec2& f : blend.frames)
        hash = fnv1aMix(hash, uint64_t(f.y) * uint64_t(mParams.frames) + uint64_t(f.x));
    }
    mSignature = hash;
  }

  OctahedralParams mParams;
  int mCellTexels = 0;
  nlohmann::json mReport;
  ImageRgba8 mColor, mNormalDepth;
  glm::vec3 mCenter{0.0f};
  float mRadius = 1.0f;
  gl::Texture mColorTexture, mNormalDepthTexture;
  gl::VertexArray mVao;
  gl::Program mProgram;
  uint64_t mSignature = 0;
  MeshCrossFade mMesh;
};

}  // namespace

void registerOctahedral(MethodRegistry& registry) {
  addMethod<OctahedralMethod, OctahedralParams>(
      registry, "octahedral",
      "octahedral impostor: one quad per tree, three of N x N atlas frames blended with depth",
      {.memoryKnob = MemoryKnob{"atlas_size", 256, 8192, true, true},
       .cost = {.bakeSeconds = 6.0, .frameCost = 0.1}});
}

}  // namespace canopy
