#include "methods/octahedral/octahedral.h"

#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "common/config.h"
#include "methods/common/dxt.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"
#include "methods/octahedral/instance_lod.h"
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
  float blendPixels = 96.0f;
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
      "1, 2 or 4: the depth and normal atlases have atlas_size / divisor texels per side");
    v("supersample", supersample, 1, 8, "capture rays per texel side (coverage and colour)");
    v("padding", padding, 1, 16, "transparent texels around each frame, so filtering stays inside");
    v("blend", blend, {"three", "nearest"},
      "three frames around the view blended by barycentric weight, or the nearest frame alone");
    v("parallax_steps", parallaxSteps, 0, 8,
      "depth reprojection steps per frame lookup (0: each frame read at the quad point)");
    v("mipmaps", mipmaps, "mipmapped atlases (coverage-preserving colour levels)");
    v("compression", compression, {"none", "dxt5"},
      "colour as BC3 (S3TC, sRGB) and normals as BC1, or both RGBA8; depth is always R8");
    v("wood", wood, "capture the trunk and branches into the frames (false: leaves only)");
    v("blend_pixels", blendPixels, 0.0f, 100000.0f,
      "an instance whose bounding radius spans fewer output pixels draws its nearest frame alone "
      "(0: every instance blends three)");
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

constexpr GLenum kLinearDxt1 = 0x83F0;  // GL_COMPRESSED_RGB_S3TC_DXT1_EXT

// A program of the impostor with its frame count compiled in (and told to the vertex shader).
struct FrameProgram {
  gl::Program program;
  int frames = 3;            // BLEND_FRAMES: 3 or 1
  std::string fragmentText;  // octahedral.frag with its constants (the program's source)
};

class OctahedralMethod final : public Method {
 public:
  explicit OctahedralMethod(OctahedralParams params)
      : mParams(std::move(params)),
        mLod(mParams.meshPixels, mParams.fadeBand, mParams.blendPixels) {
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
    findFrameRects();
    mLod.bake(tree, ctx);
    mReport = {{"frames", mParams.frames * mParams.frames},
               {"frame_texels", mCellTexels - 2 * mParams.padding},
               {"atlas", {mColor.width, mColor.height}},
               {"normal_depth_atlas", {mNormalDepth.width, mNormalDepth.height}},
               {"covered_fraction", frames.coveredFraction}};
  }

  void upload(gl::Device& device) override {
    const Compression compression = parseCompression(mParams.compression);
    mColorTexture = uploadAlphaTestedTexture(device, mColor, mParams.mipmaps, "octahedral colour",
                                             compression, CoverageTarget::kLevelZeroTest);
    uploadDepthAndNormals(device, compression);
    mRectBuffer = device.createBuffer(gl::MemoryCategory::kGeometry, GL_SHADER_STORAGE_BUFFER,
                                      mFrameRects, "octahedral frame rectangles");
    mVao = gl::createVertexArray();
    gl::api().BindVertexArray(0);
    // Three frames (unless blend is "nearest") and one; the blend and the parallax steps are
    // compiled in, so the fragment loops unroll.
    buildProgram(device, mParams.blend == "three" ? 3 : 1, mBlended);
    buildProgram(device, 1, mOneFrame);
    mLod.upload(device, device.owner() + "/frame");
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    // Near instances are the mesh (or fade into it); the impostor draws the rest.
    const std::vector<InstanceLod::State>& states =
        mLod.sortAndDrawMesh(frame, instances, mCenter, mRadius);
    updateSignature(frame, instances, states);
    const gl::Api& g = gl::api();
    const FrameProgram* current = nullptr;
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D, mColorTexture.id());
    g.ActiveTexture(GL_TEXTURE1);
    g.BindTexture(GL_TEXTURE_2D, mDepthTexture.id());
    g.ActiveTexture(GL_TEXTURE2);
    g.BindTexture(GL_TEXTURE_2D, mNormalTexture.id());
    g.BindVertexArray(mVao.id());
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, mRectBuffer.id());
    for (const InstanceLod::ImpostorDraw& draw : mLod.impostorDraws()) {
      const FrameProgram& program = draw.frames == 3 ? mBlended : mOneFrame;
      if (&program != current) setUniforms(program, frame), current = &program;
      program.program.set("uDitherKeep", draw.ditherKeep);
      bindInstanceMatrices(mLod.impostorBuffer(), 4, draw.first);
      g.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, draw.count);
    }
    g.BindVertexArray(0);
    g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    for (GLenum unit : {GL_TEXTURE2, GL_TEXTURE1}) {
      g.ActiveTexture(unit);
      g.BindTexture(GL_TEXTURE_2D, 0);
    }
    g.ActiveTexture(GL_TEXTURE0);
  }

  uint64_t lodSignature() const override { return mSignature; }
  uint64_t leafPolygonsDrawn() const override { return mLod.leafPolygonsDrawn(); }
  std::vector<uint64_t> instancesPerLevel() const override { return mLod.instancesPerState(); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mReport; }

  void save(AssetFolder& asset) const override {
    asset.describe("octahedral", effectiveParams(), mReport);
    asset.writeFields(AssetFields{mCellTexels, mCenter, mRadius});
    asset.writeImage("color.png", mColor);
    asset.writeImage("normal_depth.png", mNormalDepth);
    mLod.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("octahedral");
    AssetFields fields;
    asset.readFields(fields);
    mColor = asset.readImage("color.png");
    mNormalDepth = asset.readImage("normal_depth.png");
    asset.finishReading();
    const int side = mCellTexels * mParams.frames;
    if (fields.cellTexels != mCellTexels || mColor.width != side || mColor.height != side ||
        mNormalDepth.width != side / mParams.normalDepthDivisor ||
        mNormalDepth.height != side / mParams.normalDepthDivisor || !(fields.radius > 0.0f) ||
        !std::isfinite(fields.radius))
      throwInputError("{}: corrupt octahedral asset (atlas sizes or sphere do not match)",
                      asset.folder().string());
    mCenter = fields.center;
    mRadius = fields.radius;
    findFrameRects();
    mLod.load(asset);
  }

 private:
  OctahedralGrid grid() const { return {mParams.frames, mParams.hemisphere}; }

  // Margin: the coarsest mip level's texel (2 · padding base texels) plus its bilinear reach.
  void findFrameRects() {
    const int margin = mParams.mipmaps ? 3 * mParams.padding : 1;
    mFrameRects = frameCoverageRects(mColor, mParams.frames, mCellTexels, mParams.padding, margin);
  }

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

  // Uses `frameProgram` and sets what every draw shares.
  void setUniforms(const FrameProgram& frameProgram, const FrameContext& frame) const {
    const gl::Program& program = frameProgram.program;
    program.use();
    setFrameUniforms(program, frame);
    const glm::mat4 cameraToWorld = glm::inverse(frame.view);
    const bool orthographic = frame.projection[3][3] == 1.0f;
    program.set("uEye", glm::vec3(cameraToWorld[3]));
    program.set("uForward", -glm::normalize(glm::vec3(cameraToWorld[2])));
    program.set("uOrthographic", orthographic ? 1 : 0);
    program.set("uViewer", frame.cameraPosition);
    program.set("uLodFocalPixels", frame.lodFocalPixels);
    const int inner = mCellTexels - 2 * mParams.padding;
    // Levels past log2(padding) + 1 would mix neighbouring frames.
    program.set("uMaxLod", mParams.mipmaps ? std::log2(float(mParams.padding)) + 1.0f : 0.0f);
    program.set("uCenter", mCenter);
    program.set("uRadius", mRadius);
    program.set("uFrames", mParams.frames);
    program.set("uHemisphere", mParams.hemisphere ? 1 : 0);
    program.set("uBlendFrames", frameProgram.frames);
    program.set("uInnerTexels", float(inner));
    const float atlas = float(mCellTexels * mParams.frames);
    program.set("uCellUv", float(mCellTexels) / atlas);
    program.set("uPaddingUv", float(mParams.padding) / atlas);
    program.set("uInnerUv", float(inner) / atlas);
    program.set("uDepthLodOffset", std::log2(float(mParams.normalDepthDivisor)));
    program.set("uColor", 0);
    program.set("uDepth", 1);
    program.set("uNormals", 2);
  }

  void buildProgram(gl::Device& device, int frames, FrameProgram& out) const {
    const gl::ShaderSource& fragment = gl::embeddedShader("methods/octahedral/octahedral.frag");
    out.frames = frames;
    out.fragmentText = gl::withDefines(
        fragment.text, fmt::format("#define BLEND_FRAMES {}\n#define PARALLAX_STEPS {}\n", frames,
                                   mParams.parallaxSteps));
    out.program = device.createProgram({gl::embeddedShader("methods/octahedral/octahedral.vert"),
                                        {fragment.path, out.fragmentText}});
  }

  // The normal-depth atlas goes up as two textures: depth as R8, one byte a texel that the
  // parallax steps read uncompressed (several reads per frame and fragment), and normals, read
  // once per frame by lit frames only, as BC1 (or RGBA8 uncompressed).
  void uploadDepthAndNormals(gl::Device& device, Compression compression) {
    requireS3tcFor(compression);
    const bool compressed = compression != Compression::kNone;
    const auto create = [&](GLenum format, const char* label) {
      return device.createTexture({GL_TEXTURE_2D, mNormalDepth.width, mNormalDepth.height, 1,
                                   format, mParams.mipmaps, gl::MemoryCategory::kTexture, label});
    };
    mDepthTexture = create(GL_R8, "octahedral depth");
    mNormalTexture = create(compressed ? kLinearDxt1 : GLenum(GL_RGBA8), "octahedral normals");
    ImageRgba8 level = mNormalDepth;
    for (int l = 0; l < mDepthTexture.levels; ++l) {
      if (l > 0) level = halveImage(level);
      // Depth out of the alpha channel; the normals opaque, so BC1 keeps four colours a block.
      ImageRgba8 normals = level;
      std::vector<uint8_t> depth(level.pixels.size() / 4);
      for (size_t i = 0; i < depth.size(); ++i) {
        depth[i] = level.pixels[4 * i + 3];
        normals.pixels[4 * i + 3] = 255;
      }
      device.uploadTextureLevel(mDepthTexture, l, GL_RED, GL_UNSIGNED_BYTE, depth.data());
      if (compressed)
        device.uploadCompressedLevel(mNormalTexture, l, 0,
                                     compressImage(normals, Compression::kDxt1));
      else
        device.uploadTextureLevel(mNormalTexture, l, GL_RGBA, GL_UNSIGNED_BYTE,
                                  normals.pixels.data());
    }
    gl::setTextureSampling(mDepthTexture, true, false);
    gl::setTextureSampling(mNormalTexture, true, false);
  }

  // The frame triple each instance shows from the viewer and whether it is the mesh, fading or
  // the impostor: the popping metric's marks.
  void updateSignature(const FrameContext& frame, std::span<const Instance> instances,
                       const std::vector<InstanceLod::State>& states) {
    uint64_t hash = 0xcbf29ce484222325ull;
    const OctahedralGrid octahedralGrid = grid();
    for (size_t i = 0; i < instances.size(); ++i) {
      const Instance& instance = instances[i];
      hash = fnv1aMix(hash, static_cast<uint64_t>(states[i]));
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
  std::vector<glm::vec4> mFrameRects;  // frameCoverageRects of the colour atlas
  gl::Texture mColorTexture, mDepthTexture, mNormalTexture;
  gl::Buffer mRectBuffer;
  gl::VertexArray mVao;
  // Instances of at least blend_pixels (three frames, one when blend is "nearest") and below.
  FrameProgram mBlended, mOneFrame;
  uint64_t mSignature = 0;
  InstanceLod mLod;
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
