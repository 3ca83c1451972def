#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "common/config.h"
#include "common/error.h"
#include "common/gl/device.h"
#include "common/image.h"
#include "common/json_fields.h"
#include "common/tree.h"
#include "common/views.h"

namespace canopy {

class ProgressBar;

enum class Shading { kUnlit, kLit };

// What bake() may use besides the tree.
struct BakeContext {
  uint64_t seed = 1;                // every random choice of a bake derives from it
  ProgressBar* progress = nullptr;  // optional; methods report long loops through it
  // Renders the tree's reference image (the polygonal method) from `camera` at width × height:
  // linear premultiplied RGBA, alpha the supersampled coverage. The harness sets it; image-based
  // methods take their "photographs" of a mesh tree with it.
  std::function<ImageRgbaF(const Camera& camera, int width, int height)> photograph;
  // How the run will shade its frames: methods that bake lighting data (ambient occlusion) for
  // lit frames only may skip it for unlit runs.
  Shading shading = Shading::kUnlit;
  bool ambientOcclusion = true;  // the run's views.ambient_occlusion: false turns AO off for all
};

// Everything a draw needs to know about the frame. Instances are also in instanceBuffer (one
// mat4 per instance, column-major, in span order) so methods bind them without uploading.
//
// Level of detail is chosen in output pixels: the evaluation image a view is scored at (or the
// frame a forest is timed at), never the supersampled render target, so a view is scored at the
// LoD it is timed at. Methods read lodFocalPixels / projectedPixels for every LoD decision and
// never derive one from targetSize.
struct FrameContext {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
  glm::vec3 cameraPosition{0.0f};  // the viewer (LoD and view directions follow it)
  glm::ivec2 targetSize{0};        // the render target in pixels (supersampled): not for LoD
  // Focal length of the output image in pixels: outputHeight / (2 tan(fovY / 2)). A world length
  // s at distance d from the viewer spans s · lodFocalPixels / d output pixels.
  float lodFocalPixels = 1.0f;
  // Render-target pixels per output pixel along each axis (the supersampling factor). Shader LoD
  // that measures screen derivatives divides them by it, so it too counts output pixels.
  float targetPixelsPerOutputPixel = 1.0f;
  Shading shading = Shading::kUnlit;
  glm::vec3 lightDirection{0.3f, 0.8f, 0.5f};  // unit, towards the light (world space)
  float ambient = 0.35f;                       // ambient term of the lit shading
  bool ambientOcclusion = true;                // lit: scale the ambient term by baked AO
  GLuint instanceBuffer = 0;
  int forcedLevel = -1;  // >= 0: every method with levels of detail draws this level
  // Lit frames with shadows: the light's depth (bound by the harness to texture unit
  // kShadowMapUnit, which methods leave alone) and the light's view-projection. 0: no shadows.
  GLuint shadowMap = 0;
  glm::mat4 lightViewProjection{1.0f};
  // Dithered cross-fades (methods/common/dither.glsl): the mesh shaders keep a fragment whose
  // screen dither threshold lies in [x, y). A method that fades one instance between two of its
  // representations draws them with complementary ranges; the harness leaves it {0, 1}.
  glm::vec2 ditherKeep{0.0f, 1.0f};

  // Output pixels spanned by a world length `size` seen from `distance` (the LoD measure).
  float projectedPixels(float size, float distance) const {
    return size * lodFocalPixels / std::max(distance, 1e-6f);
  }
};

// The texture unit the shadow map is bound to during a lit, shadowed draw.
inline constexpr int kShadowMapUnit = 7;

// A baked impostor written to disk: a folder with asset.json (header) and binary blobs/images.
// Its size is the method's disk_bytes. The header is written and read in parts, each a struct
// listing its keys in visit() (common/json_fields.h): the description every asset has
// (describe/readHeaderOf), shared parts (cloud levels, the wood) and the method's own. Reading is
// strict: a missing key, a wrong type or a key no part reads (finishReading) is an InputError
// naming asset.json, so a corrupt asset is bad input (exit 2), never an internal error.
class AssetFolder {
 public:
  explicit AssetFolder(std::filesystem::path folder) : mFolder(std::move(folder)) {}
  const std::filesystem::path& folder() const { return mFolder; }
  std::string headerPath() const { return (mFolder / "asset.json").string(); }

  // Starts the header every asset has: the method, its effective parameters, its bake report
  // without timings (keys "seconds" or ending in "_s"), so one config writes the same bytes.
  void describe(const std::string& method, const nlohmann::json& params,
                const nlohmann::json& report);
  template <typename Fields>
  void writeFields(const Fields& fields) {
    mHeader.update(canopy::writeFields(fields));
  }
  void writeHeader();

  // Reads asset.json and checks it was written by `method`; returns its bake report.
  nlohmann::json readHeaderOf(const std::string& method);
  template <typename Fields>
  void readFields(Fields& fields) {
    JsonFieldReader reader(mHeader, headerPath());
    fields.visit(reader);
    mReadKeys.insert(reader.used().begin(), reader.used().end());
  }
  // InputError naming the first header key no part read.
  void finishReading() const;

  void writeBlob(const std::string& name, const void* data, size_t bytes);
  template <typename T>
  void writeBlob(const std::string& name, const std::vector<T>& data) {
    writeBlob(name, data.data(), data.size() * sizeof(T));
  }
  std::vector<uint8_t> readBlob(const std::string& name) const;
  template <typename T>
  std::vector<T> readBlobAs(const std::string& name) const {
    const std::vector<uint8_t> bytes = readBlob(name);
    if (bytes.size() % sizeof(T) != 0)
      throwInputError("{}/{}: truncated blob", mFolder.string(), name);
    std::vector<T> values(bytes.size() / sizeof(T));
    // An empty blob has no buffer: memcpy from a null pointer is undefined even for 0 bytes.
    if (!bytes.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
    return values;
  }

  void writeImage(const std::string& name, const ImageRgba8& image);
  ImageRgba8 readImage(const std::string& name) const;
  // A numbered list of images, named by `pattern` with "{}" for the index ("leaf_{}.png").
  void writeImages(const std::string& pattern, const std::vector<ImageRgba8>& images);
  std::vector<ImageRgba8> readImages(const std::string& pattern, size_t count) const;

  uint64_t sizeOnDisk() const;

 private:
  std::filesystem::path mFolder;
  nlohmann::json mHeader = nlohmann::json::object();
  std::set<std::string> mReadKeys;
};

class Method {
 public:
  virtual ~Method() = default;
  // CPU/GPU preprocessing of the tree; deterministic in ctx.seed.
  virtual void bake(const Tree& tree, BakeContext& ctx) = 0;
  // Creates every GPU resource, each through the device (and so the ledger).
  virtual void upload(gl::Device& device) = 0;
  // Draws the instances into the bound framebuffer.
  virtual void draw(const FrameContext& frame, std::span<const Instance> instances) = 0;
  // The parameters the bake really used, in the config's key names.
  virtual nlohmann::json effectiveParams() const = 0;
  // Facts about the baked representation worth a table column (cluster counts, fit errors,
  // texture sizes); added to the bake record as "report".
  virtual nlohmann::json bakeReport() const { return nlohmann::json::object(); }
  // Changes exactly when a draw picks different levels of detail than the draw before (0 for
  // methods without any): the popping metric marks those frames.
  virtual uint64_t lodSignature() const { return 0; }
  // How many of the tree's own leaves the last draw() drew as leaf polygons, over all its
  // instances (the harness divides by leaves × instances for "leaf_geometry_fraction"): every
  // leaf for the reference, 0 for a pure impostor. Counted by the draw itself, so a method that
  // wins by drawing the reference's geometry shows it.
  virtual uint64_t leafPolygonsDrawn() const { return 0; }
  // The instances the last draw() drew at each level of detail, finest first; empty for methods
  // that do not report levels. Recorded in the records' "drawn" as "instances_per_level".
  virtual std::vector<uint64_t> instancesPerLevel() const { return {}; }
  // The instances the last draw() drew at each wood level of detail, finest first (the full
  // mesh); empty for methods that always draw the full wood mesh or none.
  virtual std::vector<uint64_t> woodInstancesPerLevel() const { return {}; }
  // The baked representation, so bake and render can run apart.
  virtual void save(AssetFolder& asset) const = 0;
  virtual void load(AssetFolder& asset) = 0;
};

// Creates a method from its config parameters (an object, or null for defaults); throws
// InputError naming `configPath` and the key for unknown keys or out-of-range values.
using MethodFactory = std::function<std::unique_ptr<Method>(const nlohmann::json& params,
                                                            const std::string& configPath)>;

// The parameter that sets a method's resolution, and so its memory: what an equal-memory
// comparison ("budget") turns by bisection.
struct MemoryKnob {
  std::string parameter;
  double lo = 0.0, hi = 0.0;  // the range the bisection searches
  bool integer = false;
  bool memoryGrows = true;  // memory grows with the value (false: it shrinks, e.g. a cell size)
};

// What a (tree × method) unit is expected to cost, for balancing shards (canopy-bench --shard,
// slurm). Rough figures measured on the default run here (llvmpipe, 2 cores), at a tree of 20,000
// leaves; only their proportions matter.
struct CostHint {
  double bakeSeconds = 0.1;  // one bake
  double frameCost = 1.0;    // a frame's cost relative to the polygonal reference's
};

// What the runner needs to know about a method besides how to make it.
struct MethodTraits {
  bool needsMesh = true;  // false: bakes from images alone, so it also runs on capture folders
  std::optional<MemoryKnob> memoryKnob;  // absent: the method has no resolution to turn
  CostHint cost;
};

struct MethodInfo {
  std::string name;         // the config's "method" value
  std::string description;  // one line, for --list-methods and docs
  MethodFactory create;
  MethodTraits traits;
  std::vector<ParamDoc> parameters;  // from the Params struct's visit(): key, type, default, ...
};

// The method's parameters as a Markdown table (docs/METHODS.md holds one per method, between
// "<!-- parameters:NAME -->" and "<!-- /parameters -->"; a test checks they match) and as text
// for the terminal (--list-methods).
std::string parameterTableMarkdown(const MethodInfo& info);
std::string parameterTableText(const MethodInfo& info);

class MethodRegistry {
 public:
  void add(MethodInfo info);
  const MethodInfo& find(const std::string& name) const;  // InputError naming the known methods
  std::vector<std::string> names() const;

 private:
  std::vector<MethodInfo> mMethods;
};

// Registers MethodType, built from a Params struct read from the config (readParams: typed,
// range-checked, unknown keys rejected). Each method's register function calls it once.
template <typename MethodType, typename Params>
void addMethod(MethodRegistry& registry, const std::string& name, std::string description,
               MethodTraits traits = {}) {
  registry.add(
      {name, std::move(description),
       [name](const nlohmann::json& params, const std::string& path) -> std::unique_ptr<Method> {
         return std::make_unique<MethodType>(readParams<Params>(params, path, name));
       },
       std::move(traits), describeParams<Params>()});
}

// The registry of every built-in method, filled by registry.cpp (one explicit call each).
const MethodRegistry& builtinMethods();

// Binds `instanceBuffer` as four vec4 attributes (a mat4) starting at `location`, one per
// instance from `firstInstance` on, on the currently bound vertex array.
void bindInstanceMatrices(GLuint instanceBuffer, GLuint location, GLint firstInstance = 0);

}  // namespace canopy
