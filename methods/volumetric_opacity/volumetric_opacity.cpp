#include "methods/volumetric_opacity/volumetric_opacity.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>

#include "common/captures.h"
#include "common/progress.h"
#include "methods/volumetric_opacity/opacity_grid.h"
#include "methods/volumetric_opacity/opacity_solver.h"
#include "methods/volumetric_opacity/view_textures.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct VolumetricParams {
  int views = 22;
  int captureResolution = 512;
  float captureDistance = 3.0f;
  int level = 4;
  int texels = 8;
  float cutoff = 0.94f;
  std::string solver = "projection";
  int maxIterations = 10;
  float convergence = 0.01f;
  int rayStride = 1;
  bool inpaint = true;
  bool pack = true;
  float foregroundAlpha = 0.02f;

  template <class Visitor>
  void visit(Visitor& v) {
    v("views", views, 2, 200, "rendered photographs of a mesh tree (§4, §7: 18–22)");
    v("capture_resolution", captureResolution, 32, 4096,
      "pixels per side of each rendered photograph");
    v("capture_distance", captureDistance, 1.2f, 100.0f,
      "camera distance from the tree's centre in bounding radii");
    v("level", level, 1, 5, "grid subdivision levels, 3^level cells per side (§7: 4–5)");
    v("texels", texels, 2, 8, "M: billboard textures are M × M texels (§6: 4 or 8; memory knob)");
    v("cutoff", cutoff, 0.5f, 1.0f, "transparency cutoff threshold (§5; §7 uses 0.9 and 0.94)");
    v("solver", solver, {"projection", "ceres"},
      "projection of log-transparencies (§5, Fig. 5) or bounded least squares (ablation)");
    v("max_iterations", maxIterations, 1, 200, "solver iterations at most (§5: 3–4 suffice)");
    v("convergence", convergence, 0.0f, 1.0f,
      "stop when no transparency changes by more in an iteration");
    v("ray_stride", rayStride, 1, 16, "one ray per stride² pixels (1: every pixel, as §5)");
    v("inpaint", inpaint, "refill pixels taken by a billboard from their neighbours (§6)");
    v("pack", pack, "pack two RGB textures with disjoint alphas into one slot (§6)");
    v("foreground_alpha", foregroundAlpha, 0.0f, 0.5f,
      "alpha above which a pixel belongs to the visual hull");
  }
};

// The asset header's own part.
struct AssetFields {
  Aabb root;                                // the grid's root cube
  int level = 0;                            // subdivision levels
  std::vector<int> cellsPerLevel;           // non-empty cells per level
  std::vector<glm::vec3> cameraDirections;  // of the input views, unit
  int texels = 0;                           // M
  template <class V>
  void visit(V& v) {
    v("root", root);
    v("level", level);
    v("cells_per_level", cellsPerLevel);
    v("camera_directions", cameraDirections);
    v("texels", texels);
  }
};

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// 26 directions (faces, edges and corners of a cube): each has the cells sorted back to front
// for a viewer far along it; a draw uses the one nearest its viewing direction.
std::vector<glm::vec3> orderDirections() {
  std::vector<glm::vec3> directions;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x || y || z) directions.push_back(glm::normalize(glm::vec3(x, y, z)));
  return directions;
}

class VolumetricOpacity final : public Method {
 public:
  explicit VolumetricOpacity(VolumetricParams params) : mParams(std::move(params)) {}

  void bake(const Tree& tree, BakeContext& ctx) override {
    mReport = nlohmann::json::object();
    // §4: the input views — the capture's training views, or photographs of the mesh.
    auto start = Clock::now();
    std::vector<CapturedView> rendered;
    const std::vector<CapturedView>* inputs = nullptr;
    if (tree.captures) {
      inputs = &tree.captures->train;
      mReport["input"] = "captures";
    } else {
      if (!ctx.photograph)
        throw std::logic_error("volumetric_opacity: bake needs BakeContext::photograph");
      for (const Camera& camera :
           captureRingCameras(tree.bounds, mParams.views, mParams.captureDistance, 5.0f)) {
        rendered.push_back(
            {camera, ctx.photograph(camera, mParams.captureResolution, mParams.captureResolution),
             fmt::format("view {}", rendered.size())});
      }
      inputs = &rendered;
      mReport["input"] = "rendered";
    }
    mReport["input_views"] = inputs->size();
    mReport["capture_s"] = secondsSince(start);
    const std::vector<OpacityView> views = prepareViews(*inputs, mParams.foregroundAlpha);
    mCameraDirections.clear();
    const Aabb& bounds = tree.captures ? tree.captures->bounds : tree.bounds;
    for (const CapturedView& v : *inputs)
      mCameraDirections.push_back(glm::normalize(v.camera.position - bounds.center()));

    // §7 grid and §5 initialisation and estimation.
    start = Clock::now();
    mGrid = buildOpacityGrid(enclosingCube(bounds), mParams.level, views, mParams.foregroundAlpha);
    mReport["cells_per_level"] = mGrid.nonEmptyPerLevel;
    mReport["grid_s"] = secondsSince(start);
    spdlog::info("volumetric_opacity: {} cells inside the visual hull at level {} ({:.2f} s)",
                 mGrid.cells.size(), mParams.level, mReport["grid_s"].get<double>());
    SolverSettings solver{mParams.maxIterations, mParams.convergence, mParams.cutoff,
                          mParams.rayStride};
    const double initialResidual = transparencyResidual(mGrid, views, mParams.rayStride);
    const SolverResult solved = mParams.solver == "ceres" ? solveWithCeres(mGrid, views, solver)
                                                          : solveByProjection(mGrid, views, solver);
    nlohmann::json iterations = nlohmann::json::array();
    for (const SolverIteration& it : solved.iterations)
      iterations.push_back({{"rms_transparency", it.rmsTransparency},
                            {"rms_log", it.rmsLog},
                            {"max_change", it.maxChange},
                            {"active_cells", it.activeCells},
                            {"seconds", it.seconds}});
    mGrid.removeTransparentCells(1.0f);
    mReport["estimation"] = {{"solver", solved.solver},
                             {"rays", solved.rays},
                             {"initial_rms_transparency", initialResidual},
                             {"final_rms_transparency", solved.finalRmsTransparency},
                             {"converged", solved.converged},
                             {"iterations", iterations},
                             {"seconds", solved.seconds}};
    mReport["cells"] = mGrid.cells.size();
    spdlog::info("volumetric_opacity: {} cells after the cutoff {}; residual {:.4f} → {:.4f}",
                 mGrid.cells.size(), mParams.cutoff, initialResidual, solved.finalRmsTransparency);

    // §6 view-dependent textures, then packing.
    start = Clock::now();
    const ViewTextures textures =
        generateViewTextures(mGrid, views, {mParams.texels, mParams.inpaint, 2});
    const double texturesSeconds = secondsSince(start);
    start = Clock::now();
    if (mParams.pack) {
      mTextures = packTextures(textures);
    } else {
      mTextures = {textures.texels, textures.tile, textures.alpha, {}, textures.rgb};
      mTextures.slotOfTile.resize(textures.tileCount());
      std::iota(mTextures.slotOfTile.begin(), mTextures.slotOfTile.end(), 0u);
    }
    const double packingSeconds = secondsSince(start);
    const uint64_t texelsPerTexture = uint64_t(mParams.texels) * mParams.texels;
    mReport["textures"] = {
        {"texels", mParams.texels},
        {"all_textures", uint64_t(textures.views) * textures.cells},
        {"non_empty_textures", textures.tileCount()},
        {"rgba_bytes_all", uint64_t(textures.views) * textures.cells * texelsPerTexture * 4},
        {"rgba_bytes_non_empty", textures.tileCount() * texelsPerTexture * 4},
        {"rgb_slots", mTextures.slotCount()},
        {"packed_bytes", mTextures.texelBytes()},
        {"generation_s", texturesSeconds},
        {"packing_s", packingSeconds}};
    spdlog::info(
        "volumetric_opacity: {} non-empty textures of {} ({:.1f} MB RGBA), packed into {} RGB "
        "slots: {:.1f} MB; textures {:.2f} s, packing {:.2f} s",
        textures.tileCount(), uint64_t(textures.views) * textures.cells,
        double(textures.tileCount() * texelsPerTexture * 4) / 1e6, mTextures.slotCount(),
        double(mTextures.texelBytes()) / 1e6, texturesSeconds, packingSeconds);
    buildOrders();
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    std::vector<uint32_t> coords(mGrid.cells.size());
    for (size_t i = 0; i < coords.size(); ++i) {
      const glm::ivec3 c = mGrid.cells[i];
      coords[i] = uint32_t(c.x) | uint32_t(c.y) << 10 | uint32_t(c.z) << 20;
    }
    const auto storage = [&](MemoryCategory category, const auto& data, const char* label) {
      // Storage buffers may not be empty; one word stands in for nothing.
      const size_t bytes = std::max<size_t>(data.size() * sizeof(data[0]), 4);
      std::vector<uint8_t> padded(bytes + (4 - bytes % 4) % 4, 0);
      if (!data.empty()) std::memcpy(padded.data(), data.data(), data.size() * sizeof(data[0]));
      return device.createBuffer(category, GL_SHADER_STORAGE_BUFFER, padded, label);
    };
    mBuffers[0] = storage(MemoryCategory::kGeometry, coords, "cell coordinates");
    mBuffers[1] = storage(MemoryCategory::kGeometry, mOrders, "back-to-front orders");
    mBuffers[2] = storage(MemoryCategory::kOther, mTextures.tile, "texture of each cell and view");
    mBuffers[3] = storage(MemoryCategory::kOther, mTextures.slotOfTile, "RGB slot of each texture");
    mBuffers[4] = storage(MemoryCategory::kTexture, mTextures.alpha, "billboard alphas");
    mBuffers[5] = storage(MemoryCategory::kTexture, mTextures.slotRgb, "billboard colours");
    mProgram =
        device.createProgram({gl::embeddedShader("methods/volumetric_opacity/billboards.vert"),
                              gl::embeddedShader("methods/volumetric_opacity/billboards.frag")});
    mVao = gl::createVertexArray();  // attribute-less draws still need one in a core context
    gl::api().BindVertexArray(0);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty() || mGrid.cells.empty()) return;
    const gl::Api& g = gl::api();
    mProgram.use();
    mProgram.set("uView", frame.view);
    mProgram.set("uProjection", frame.projection);
    mProgram.set("uRootMin", mGrid.root.min);
    mProgram.set("uCellSize", mGrid.cellSize);
    mProgram.set("uCells", int(mGrid.cells.size()));
    mProgram.set("uTexels", mTextures.texels);
    const glm::vec3 right(frame.view[0][0], frame.view[1][0], frame.view[2][0]);
    const glm::vec3 up(frame.view[0][1], frame.view[1][1], frame.view[2][1]);
    mProgram.set("uRight", right);
    mProgram.set("uUp", up);
    for (GLuint b = 0; b < mBuffers.size(); ++b)
      g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, b, mBuffers[b].id());
    g.BindVertexArray(mVao.id());
    // Over operator on premultiplied colour, back to front, no depth writes (§6).
    g.Enable(GL_BLEND);
    g.BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    g.DepthMask(GL_FALSE);
    // Trees far to near so the forest composites correctly too.
    std::vector<size_t> order(instances.size());
    std::iota(order.begin(), order.end(), 0);
    std::vector<float> distance(instances.size());
    for (size_t i = 0; i < instances.size(); ++i)
      distance[i] = glm::length(instances[i].position - frame.cameraPosition);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return distance[a] > distance[b]; });
    const glm::vec3 center = mGrid.root.center();
    for (size_t i : order) {
      const glm::mat4 model = instances[i].modelMatrix();
      const glm::mat3 toModel = glm::inverse(glm::mat3(model));
      const glm::vec3 viewer =
          glm::vec3(glm::affineInverse(model) * glm::vec4(frame.cameraPosition, 1));
      const glm::vec3 direction = glm::normalize(viewer - center);
      const auto [camera0, camera1, weight0] = closestCameras(direction);
      const float scale = glm::length(glm::vec3(model[0]));
      const glm::vec2 half =
          scale * billboardHalfExtents(mGrid.cellSize, glm::normalize(toModel * right),
                                       glm::normalize(toModel * up));
      mProgram.set("uModel", model);
      mProgram.set("uHalf", half);
      mProgram.set("uCamera0", camera0);
      mProgram.set("uCamera1", camera1);
      mProgram.set("uWeight0", weight0);
      mProgram.set("uWeight1", 1.0f - weight0);
      mProgram.set("uOrderOffset", int(nearestOrder(direction) * mGrid.cells.size()));
      g.DrawArrays(GL_TRIANGLES, 0, GLsizei(mGrid.cells.size() * 6));
    }
    g.DepthMask(GL_TRUE);
    g.Disable(GL_BLEND);
    g.BindVertexArray(0);
  }

  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mReport; }

  void save(AssetFolder& asset) const override {
    asset.describe("volumetric_opacity", effectiveParams(), mReport);
    asset.writeFields(AssetFields{mGrid.root, mGrid.level, mGrid.nonEmptyPerLevel,
                                  mCameraDirections, mTextures.texels});
    asset.writeBlob("cells.bin", mGrid.cells);
    asset.writeBlob("transparency.bin", mGrid.transparency);
    asset.writeBlob("tile_of_cell_view.bin", mTextures.tile);
    asset.writeBlob("alpha.bin", mTextures.alpha);
    asset.writeBlob("slot_of_tile.bin", mTextures.slotOfTile);
    asset.writeBlob("slot_rgb.bin", mTextures.slotRgb);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("volumetric_opacity");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    mGrid = {};
    mGrid.root = fields.root;
    mGrid.level = fields.level;
    if (mGrid.level < 1 || mGrid.level > 5) throwInputError("{}: level out of range", folder);
    mGrid.side = 1;
    for (int l = 0; l < mGrid.level; ++l) mGrid.side *= 3;
    mGrid.cellSize = mGrid.root.extent().x / float(mGrid.side);
    mGrid.nonEmptyPerLevel = fields.cellsPerLevel;
    mCameraDirections = fields.cameraDirections;
    mTextures = {};
    mTextures.texels = fields.texels;
    mGrid.cells = asset.readBlobAs<glm::ivec3>("cells.bin");
    mGrid.transparency = asset.readBlobAs<float>("transparency.bin");
    mTextures.tile = asset.readBlobAs<uint32_t>("tile_of_cell_view.bin");
    mTextures.alpha = asset.readBlobAs<uint8_t>("alpha.bin");
    mTextures.slotOfTile = asset.readBlobAs<uint32_t>("slot_of_tile.bin");
    mTextures.slotRgb = asset.readBlobAs<uint8_t>("slot_rgb.bin");
    // Every index the shaders follow is checked here, so a corrupt asset cannot read past a buffer.
    const size_t texelCount = size_t(mTextures.texels) * mTextures.texels;
    const size_t tiles = mTextures.alpha.size() / std::max<size_t>(texelCount, 1);
    bool valid = mTextures.texels >= 2 && mTextures.texels <= 8 && !mCameraDirections.empty() &&
                 mGrid.transparency.size() == mGrid.cells.size() &&
                 mTextures.tile.size() == mCameraDirections.size() * mGrid.cells.size() &&
                 mTextures.alpha.size() == tiles * texelCount &&
                 mTextures.slotOfTile.size() == tiles;
    for (const glm::ivec3& c : mGrid.cells)
      valid = valid && glm::all(glm::greaterThanEqual(c, glm::ivec3(0))) &&
              glm::all(glm::lessThan(c, glm::ivec3(mGrid.side)));
    for (uint32_t t : mTextures.tile) valid = valid && (t == kNoTile || t < tiles);
    for (uint32_t s : mTextures.slotOfTile) valid = valid && s < mTextures.slotCount();
    if (!valid) throwInputError("{}: corrupt volumetric_opacity asset", folder);
    mGrid.rebuildLattice();
    buildOrders();
    asset.finishReading();
  }

 private:
  void buildOrders() {
    const std::vector<glm::vec3> directions = orderDirections();
    const size_t n = mGrid.cells.size();
    mOrders.assign(directions.size() * n, 0);
    std::vector<float> key(n);
    for (size_t d = 0; d < directions.size(); ++d) {
      for (size_t c = 0; c < n; ++c) key[c] = glm::dot(mGrid.cellCenter(c), directions[d]);
      auto begin = mOrders.begin() + std::ptrdiff_t(d * n);
      std::iota(begin, begin + std::ptrdiff_t(n), 0u);
      // Farthest from a viewer along +direction first.
      std::stable_sort(begin, begin + std::ptrdiff_t(n),
                       [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
    }
  }

  size_t nearestOrder(const glm::vec3& direction) const {
    static const std::vector<glm::vec3> directions = orderDirections();
    size_t best = 0;
    for (size_t d = 1; d < directions.size(); ++d)
      if (glm::dot(directions[d], direction) > glm::dot(directions[best], direction)) best = d;
    return best;
  }

  // The two input cameras closest in direction and the first one's weight, by angle (§6,
  // [Debevec et al. 1996]): w0 = θ1 / (θ0 + θ1).
  std::tuple<int, int, float> closestCameras(const glm::vec3& direction) const {
    int first = -1, second = -1;
    float angleFirst = 10.0f, angleSecond = 10.0f;
    for (size_t c = 0; c < mCameraDirections.size(); ++c) {
      const float angle =
          std::acos(std::clamp(glm::dot(mCameraDirections[c], direction), -1.0f, 1.0f));
      if (angle < angleFirst) {
        second = first, angleSecond = angleFirst;
        first = int(c), angleFirst = angle;
      } else if (angle < angleSecond) {
        second = int(c), angleSecond = angle;
      }
    }
    if (second < 0) return {first, first, 1.0f};
    const float sum = angleFirst + angleSecond;
    return {first, second, sum > 1e-6f ? angleSecond / sum : 1.0f};
  }

  VolumetricParams mParams;
  nlohmann::json mReport;
  OpacityGrid mGrid;
  PackedTextures mTextures;
  std::vector<glm::vec3> mCameraDirections;  // unit, from the grid centre to each input camera
  std::vector<uint32_t> mOrders;             // 26 × cells, back to front per direction
  std::array<gl::Buffer, 6> mBuffers;
  gl::Program mProgram;
  gl::VertexArray mVao;
};

}  // namespace

void registerVolumetricOpacity(MethodRegistry& registry) {
  addMethod<VolumetricOpacity, VolumetricParams>(
      registry, "volumetric_opacity",
      "volumetric opacity reconstruction with view-dependent billboards (Reche-Martinez, Martin, "
      "Drettakis 2004)",
      {.needsMesh = false,
       .memoryKnob = MemoryKnob{"texels", 2, 8, true, true},
       .cost = {.bakeSeconds = 20.0, .frameCost = 6.0}});
}

}  // namespace canopy
