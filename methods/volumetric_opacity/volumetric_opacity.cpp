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
#include "methods/common/dxt.h"
#include "methods/common/lod_instances.h"
#include "methods/volumetric_opacity/opacity_grid.h"
#include "methods/volumetric_opacity/opacity_solver.h"
#include "methods/volumetric_opacity/view_textures.h"
#include "methods/volumetric_opacity/volumetric_levels.h"

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
  int maxIterations = 4;
  float convergence = 0.01f;
  int rayStride = 1;
  std::string selection = "partition";
  float hiddenCutoff = 0.02f;
  float frontEmphasis = 0.0f;
  bool inpaint = true;
  int lodLevels = 3;
  float lodCellPixels = 8.0f;
  std::string compression = "dxt5";
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
    v("selection", selection, {"partition", "paper"},
      "texels: each pixel's alpha split among the cells on its ray (partition) or §6's "
      "age/importance selection of ⌊α_c·M²⌋ texels (paper)");
    v("hidden_cutoff", hiddenCutoff, 0.0f, 0.5f,
      "partition: drop a (cell, view) texture whose every texel adds less alpha than this "
      "behind the cells in front of it");
    v("front_emphasis", frontEmphasis, 0.0f, 16.0f,
      "partition: a cell's share of a pixel's alpha is weighted by exp(−this · optical depth in "
      "front of it), so the first cells a ray meets take more (0: optical depth alone)");
    v("inpaint", inpaint, "paper selection: refill pixels taken by a billboard (§6)");
    v("lod_levels", lodLevels, 1, 3,
      "levels of detail: the grid's level and coarser ones of the recursive grid, not below 2");
    v("lod_cell_pixels", lodCellPixels, 0.25f, 64.0f,
      "an instance draws the coarsest level whose cells span at most this many output pixels");
    v("compression", compression, {"none", "dxt5"},
      "the billboard atlas as sRGB RGBA8 or S3TC DXT5 (BC3, 4:1)");
    v("foreground_alpha", foregroundAlpha, 0.0f, 0.5f,
      "alpha above which a pixel belongs to the visual hull");
  }
};

// The asset header's own part.
struct AssetFields {
  Aabb root;                                // the grid's root cube
  std::vector<int> levels;                  // grid level of each level of detail, finest first
  std::vector<int> cellsPerLevel;           // non-empty cells per level of the finest grid
  std::vector<glm::vec3> cameraDirections;  // of the input views, unit
  std::vector<glm::vec3> cameraRight;       // image axes of the input views, unit
  std::vector<glm::vec3> cameraUp;
  int texels = 0;           // M
  std::string compression;  // of the atlas: "none" or "dxt5"
  template <class V>
  void visit(V& v) {
    v("root", root);
    v("levels", levels);
    v("cells_per_level", cellsPerLevel);
    v("camera_directions", cameraDirections);
    v("camera_right", cameraRight);
    v("camera_up", cameraUp);
    v("texels", texels);
    v("compression", compression);
  }
};

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The roll-compensated texture frame of one input camera for a viewer along `viewer`: the
// camera's image axes turned by the smallest rotation taking its direction onto the viewer's,
// so its billboard texture keeps its orientation around the view axis (§6 leaves the roll out).
struct CameraFrame {
  glm::vec3 right, up;
  glm::vec2 half;  // the cell's billboard half extents in this camera's axes
};
CameraFrame cameraFrame(const glm::vec3& cameraDirection, const glm::vec3& right,
                        const glm::vec3& up, const glm::vec3& viewer, float cellSize) {
  const glm::vec3 axis = glm::cross(cameraDirection, viewer);
  const float sine = glm::length(axis), cosine = glm::dot(cameraDirection, viewer);
  const auto rotate = [&](const glm::vec3& v) {
    if (sine < 1e-6f) return v;
    const glm::vec3 k = axis / sine;  // Rodrigues
    return v * cosine + glm::cross(k, v) * sine + k * glm::dot(k, v) * (1.0f - cosine);
  };
  return {rotate(right), rotate(up), billboardHalfExtents(cellSize, right, up)};
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
    const Aabb& bounds = tree.captures ? tree.captures->bounds : tree.bounds;

    // §7 grid and §5 initialisation and estimation.
    start = Clock::now();
    OpacityGrid grid =
        buildOpacityGrid(enclosingCube(bounds), mParams.level, views, mParams.foregroundAlpha);
    mReport["cells_per_level"] = grid.nonEmptyPerLevel;
    mReport["grid_s"] = secondsSince(start);
    spdlog::info("volumetric_opacity: {} cells inside the visual hull at level {} ({:.2f} s)",
                 grid.cells.size(), mParams.level, mReport["grid_s"].get<double>());
    estimate(grid, views);

    // §6 view-dependent textures of every level of detail, in one atlas.
    start = Clock::now();
    const TextureSettings textures{
        mParams.texels,
        mParams.selection == "paper" ? TexelSelection::kPaper : TexelSelection::kPartition,
        mParams.hiddenCutoff,
        mParams.frontEmphasis,
        mParams.inpaint,
        2};
    mModel = buildVolumetricModel(
        std::move(grid), views,
        {mParams.lodLevels, textures, parseCompression(mParams.compression), kMaxPageSize},
        SolverSettings{}.minTransparency);
    for (const OpacityView& v : views) {
      mModel.cameraDirections.push_back(glm::normalize(v.camera.position() - bounds.center()));
      mModel.cameraRight.push_back(v.camera.right());
      mModel.cameraUp.push_back(v.camera.up());
    }
    mReport["textures_s"] = secondsSince(start);
    reportTextures();
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    std::vector<uint32_t> coords, tiles;
    mLevelBases.clear();
    for (const VolumetricLevel& level : mModel.levels) {
      mLevelBases.push_back({coords.size(), tiles.size()});
      for (const glm::ivec3& c : level.grid.cells)
        coords.push_back(uint32_t(c.x) | uint32_t(c.y) << 10 | uint32_t(c.z) << 20);
      tiles.insert(tiles.end(), level.table.begin(), level.table.end());
    }
    mOrders = packOrders(mModel.levels);
    std::vector<uint32_t> orders = mOrders.words;
    const auto storage = [&](MemoryCategory category, std::vector<uint32_t>& data,
                             const char* label) {
      // Storage buffers may not be empty; one word stands in for nothing.
      if (data.empty()) data.push_back(0);
      return device.createBuffer(category, GL_SHADER_STORAGE_BUFFER, data, label);
    };
    mBuffers[0] = storage(MemoryCategory::kGeometry, coords, "cell coordinates of every level");
    mBuffers[1] = storage(MemoryCategory::kGeometry, orders, "back-to-front orders");
    mBuffers[2] = storage(MemoryCategory::kOther, tiles, "first tile and view mask of each cell");
    const TileAtlas& atlas = mModel.atlas;
    requireS3tcFor(mModel.compression);
    mAtlas = device.createTexture({GL_TEXTURE_2D_ARRAY, atlas.pageSize, atlas.pageSize,
                                   int(atlas.pages.size()), srgbInternalFormat(mModel.compression),
                                   false, MemoryCategory::kTexture, "billboard atlas"});
    for (size_t p = 0; p < atlas.pages.size(); ++p) {
      if (mModel.compression == Compression::kNone)
        device.uploadTextureLayer(mAtlas, int(p), GL_RGBA, GL_UNSIGNED_BYTE,
                                  atlas.pages[p].pixels.data());
      else
        device.uploadCompressedLevel(mAtlas, 0, int(p), mModel.compressedPages[p]);
    }
    gl::setTextureSampling(mAtlas, true, false);
    mProgram =
        device.createProgram({gl::embeddedShader("methods/volumetric_opacity/billboards.vert"),
                              gl::embeddedShader("methods/volumetric_opacity/billboards.frag")});
    mVao = gl::createVertexArray();  // attribute-less draws still need one in a core context
    gl::api().BindVertexArray(0);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    mSignature = 0;
    mInstancesPerLevel.assign(mModel.levels.size(), 0);
    if (instances.empty() || mModel.levels.empty() || mModel.levels[0].grid.cells.empty()) return;
    const gl::Api& g = gl::api();
    mProgram.use();
    mProgram.set("uView", frame.view);
    mProgram.set("uProjection", frame.projection);
    mProgram.set("uTexels", mModel.atlas.texels);
    mProgram.set("uTilesPerRow", mModel.atlas.tilesPerRow);
    mProgram.set("uPageSize", float(mModel.atlas.pageSize));
    mProgram.set("uAtlas", 0);
    for (GLuint b = 0; b < mBuffers.size(); ++b)
      g.BindBufferBase(GL_SHADER_STORAGE_BUFFER, b, mBuffers[b].id());
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D_ARRAY, mAtlas.id());
    g.BindVertexArray(mVao.id());
    // Over operator on premultiplied colour, back to front, no depth writes (§6).
    g.Enable(GL_BLEND);
    g.BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    g.DepthMask(GL_FALSE);
    // Trees far to near so the forest composites correctly too.
    std::vector<float> distance(instances.size());
    for (size_t i = 0; i < instances.size(); ++i)
      distance[i] = glm::length(instances[i].position - frame.cameraPosition);
    std::vector<size_t> order(instances.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return distance[a] > distance[b]; });
    for (size_t i : order) drawInstance(frame, instances[i], distance[i]);
    g.DepthMask(GL_TRUE);
    g.Disable(GL_BLEND);
    g.BindTexture(GL_TEXTURE_2D_ARRAY, 0);
    g.BindVertexArray(0);
  }

  uint64_t lodSignature() const override { return mSignature; }
  std::vector<uint64_t> instancesPerLevel() const override { return mInstancesPerLevel; }

  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mReport; }

  void save(AssetFolder& asset) const override {
    asset.describe("volumetric_opacity", effectiveParams(), mReport);
    AssetFields fields{mModel.levels.front().grid.root,
                       {},
                       mModel.levels.front().grid.nonEmptyPerLevel,
                       mModel.cameraDirections,
                       mModel.cameraRight,
                       mModel.cameraUp,
                       mModel.atlas.texels,
                       mParams.compression};
    for (const VolumetricLevel& level : mModel.levels) fields.levels.push_back(level.grid.level);
    asset.writeFields(fields);
    for (size_t l = 0; l < mModel.levels.size(); ++l) {
      const VolumetricLevel& level = mModel.levels[l];
      asset.writeBlob(fmt::format("cells_{}.bin", l), level.grid.cells);
      asset.writeBlob(fmt::format("transparency_{}.bin", l), level.grid.transparency);
      asset.writeBlob(fmt::format("tile_table_{}.bin", l), level.table);
    }
    asset.writeBlob("tiles_rgba.bin", mModel.tiles);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override;

 private:
  static constexpr int kMaxPageSize = 1024;  // 16,384 tiles of 8² a page: little left empty

  // §5: the solve, its best iterate kept, then the cells above the cutoff emptied.
  void estimate(OpacityGrid& grid, const std::vector<OpacityView>& views) {
    SolverSettings solver{mParams.maxIterations, mParams.convergence, mParams.cutoff,
                          mParams.rayStride};
    const double initialResidual = transparencyResidual(grid, views, mParams.rayStride);
    const SolverResult solved = mParams.solver == "ceres" ? solveWithCeres(grid, views, solver)
                                                          : solveByProjection(grid, views, solver);
    nlohmann::json iterations = nlohmann::json::array();
    for (const SolverIteration& it : solved.iterations)
      iterations.push_back({{"rms_transparency", it.rmsTransparency},
                            {"rms_log", it.rmsLog},
                            {"max_change", it.maxChange},
                            {"active_cells", it.activeCells},
                            {"seconds", it.seconds}});
    grid.removeTransparentCells(1.0f);
    mReport["estimation"] = {{"solver", solved.solver},
                             {"rays", solved.rays},
                             {"initial_rms_transparency", initialResidual},
                             {"final_rms_transparency", solved.finalRmsTransparency},
                             {"converged", solved.converged},
                             {"stop_reason", solved.stopReason},
                             {"best_iteration", solved.bestIteration},
                             {"iterations", iterations},
                             {"seconds", solved.seconds}};
    mReport["cells"] = grid.cells.size();
    spdlog::info(
        "volumetric_opacity: {} cells after the cutoff {}; residual {:.4f} → {:.4f} "
        "(iterate {} kept: {})",
        grid.cells.size(), mParams.cutoff, initialResidual, solved.finalRmsTransparency,
        solved.bestIteration, solved.stopReason);
  }

  // The bake record's texture facts and memory by part (bytes as uploaded).
  void reportTextures() {
    nlohmann::json levels = nlohmann::json::array();
    uint64_t tableBytes = 0, geometryBytes = 0;
    const size_t views = mModel.cameraDirections.size();
    for (const VolumetricLevel& level : mModel.levels) {
      size_t kept = 0;
      for (size_t c = 0; c < level.grid.cells.size(); ++c)
        kept += tilesClaimed(level.table, views, c);
      levels.push_back({{"grid_level", level.grid.level},
                        {"cells", level.grid.cells.size()},
                        {"all_textures", views * level.grid.cells.size()},
                        {"kept_textures", kept},
                        {"empty_textures", level.emptyTiles},
                        {"hidden_textures", level.hiddenTiles}});
      tableBytes += level.table.size() * 4;
      geometryBytes += level.grid.cells.size() * 4;  // the packed coordinates
    }
    geometryBytes += packOrders(mModel.levels).words.size() * 4;
    const uint64_t atlasBytes = mModel.textureBytes();
    mReport["levels"] = levels;
    mReport["textures"] = {{"texels", mParams.texels},
                           {"tiles", mModel.tileCount()},
                           {"atlas_pages", mModel.atlas.pages.size()},
                           {"atlas_page_size", mModel.atlas.pageSize},
                           {"compression", mParams.compression}};
    mReport["memory_by_part"] = {{"atlas_bytes", atlasBytes},
                                 {"tile_table_bytes", tableBytes},
                                 {"cells_and_orders_bytes", geometryBytes}};
    spdlog::info(
        "volumetric_opacity: {} textures in {} atlas pages of {}²: atlas {:.1f} MB, tables "
        "{:.1f} MB, cells and orders {:.1f} MB ({:.2f} s)",
        mModel.tileCount(), mModel.atlas.pages.size(), mModel.atlas.pageSize,
        double(atlasBytes) / 1e6, double(tableBytes) / 1e6, double(geometryBytes) / 1e6,
        mReport["textures_s"].get<double>());
  }

  // The level an instance draws: the coarsest whose cells span at most lod_cell_pixels output
  // pixels at the instance's distance (the fair-harness rule), or the forced one.
  size_t levelFor(const FrameContext& frame, float scale, float distance) const {
    if (frame.forcedLevel >= 0)
      return std::min(size_t(frame.forcedLevel), mModel.levels.size() - 1);
    size_t chosen = 0;
    for (size_t l = 1; l < mModel.levels.size(); ++l)
      if (frame.projectedPixels(scale * mModel.levels[l].grid.cellSize, distance) <=
          mParams.lodCellPixels)
        chosen = l;
    return chosen;
  }

  void drawInstance(const FrameContext& frame, const Instance& instance, float distance) {
    const glm::mat4 model = instance.modelMatrix();
    const float scale = glm::length(glm::vec3(model[0]));
    const size_t l = levelFor(frame, scale, distance);
    ++mInstancesPerLevel[l];
    mSignature = fnv1aMix(mSignature, l + 1);
    const VolumetricLevel& level = mModel.levels[l];
    if (level.grid.cells.empty()) return;
    const LevelBases& bases = mLevelBases[l];
    const glm::mat3 toModel = glm::inverse(glm::mat3(model));
    const glm::vec3 right =
        glm::normalize(toModel * glm::vec3(frame.view[0][0], frame.view[1][0], frame.view[2][0]));
    const glm::vec3 up =
        glm::normalize(toModel * glm::vec3(frame.view[0][1], frame.view[1][1], frame.view[2][1]));
    const glm::vec3 viewer =
        glm::vec3(glm::affineInverse(model) * glm::vec4(frame.cameraPosition, 1));
    const glm::vec3 direction = glm::normalize(viewer - level.grid.root.center());
    const auto [camera0, camera1, weight0] = closestCameras(direction);
    const float cellSize = level.grid.cellSize;
    const CameraFrame frames[2] = {
        cameraFrame(mModel.cameraDirections[size_t(camera0)], mModel.cameraRight[size_t(camera0)],
                    mModel.cameraUp[size_t(camera0)], direction, cellSize),
        cameraFrame(mModel.cameraDirections[size_t(camera1)], mModel.cameraRight[size_t(camera1)],
                    mModel.cameraUp[size_t(camera1)], direction, cellSize)};
    // The quad, in the viewer's axes, holds both cameras' turned billboards.
    glm::vec2 half = billboardHalfExtents(cellSize, right, up);
    for (const CameraFrame& f : frames) {
      half.x = std::max(half.x, std::abs(glm::dot(f.right, right)) * f.half.x +
                                    std::abs(glm::dot(f.up, right)) * f.half.y);
      half.y = std::max(half.y, std::abs(glm::dot(f.right, up)) * f.half.x +
                                    std::abs(glm::dot(f.up, up)) * f.half.y);
    }
    mProgram.set("uModel", model);
    mProgram.set("uRootMin", level.grid.root.min);
    mProgram.set("uCellSize", cellSize);
    mProgram.set("uCellBase", int(bases.cell));
    mProgram.set("uTileBase", int(bases.table));
    mProgram.set("uTableStride", int(tableStride(mModel.cameraDirections.size())));
    const auto [orderFirst, orderReversed] =
        mOrders.lookup(l, nearestOrder(direction), level.grid.cells.size());
    mProgram.set("uOrderOffset", int(orderFirst));
    mProgram.set("uOrderReversed", orderReversed ? 1 : 0);
    mProgram.set("uOrders16", mOrders.sixteenBit ? 1 : 0);
    mProgram.set("uCellCount", int(level.grid.cells.size()));
    mProgram.set("uQuadRight", right);
    mProgram.set("uQuadUp", up);
    mProgram.set("uQuadHalf", half);
    mProgram.set("uCamera0", camera0);
    mProgram.set("uCamera1", camera1);
    mProgram.set("uAxisRight0", frames[0].right / frames[0].half.x);
    mProgram.set("uAxisUp0", frames[0].up / frames[0].half.y);
    mProgram.set("uAxisRight1", frames[1].right / frames[1].half.x);
    mProgram.set("uAxisUp1", frames[1].up / frames[1].half.y);
    mProgram.set("uWeight0", weight0);
    mProgram.set("uWeight1", 1.0f - weight0);
    gl::api().DrawArrays(GL_TRIANGLES, 0, GLsizei(level.grid.cells.size() * 6));
  }

  // The two input cameras closest in direction and the first one's weight, by angle (§6,
  // [Debevec et al. 1996]): w0 = θ1 / (θ0 + θ1).
  std::tuple<int, int, float> closestCameras(const glm::vec3& direction) const {
    int first = -1, second = -1;
    float angleFirst = 10.0f, angleSecond = 10.0f;
    for (size_t c = 0; c < mModel.cameraDirections.size(); ++c) {
      const float angle =
          std::acos(std::clamp(glm::dot(mModel.cameraDirections[c], direction), -1.0f, 1.0f));
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
  VolumetricModel mModel;
  std::array<gl::Buffer, 3> mBuffers;
  gl::Texture mAtlas;
  gl::Program mProgram;
  gl::VertexArray mVao;
  // Where each level starts in the shared storage buffers (set at upload).
  struct LevelBases {
    size_t cell, table;
  };
  std::vector<LevelBases> mLevelBases;
  PackedOrders mOrders;  // the back-to-front orders as uploaded
  uint64_t mSignature = 0;
  std::vector<uint64_t> mInstancesPerLevel;  // of the last draw
};

void VolumetricOpacity::load(AssetFolder& asset) {
  mReport = asset.readHeaderOf("volumetric_opacity");
  AssetFields fields;
  asset.readFields(fields);
  const std::string folder = asset.folder().string();
  const size_t views = fields.cameraDirections.size();
  bool valid = (fields.compression == "none" || fields.compression == "dxt5") &&
               fields.texels >= 2 && fields.texels <= 8 && views > 0 &&
               fields.cameraRight.size() == views && fields.cameraUp.size() == views &&
               !fields.levels.empty() && fields.levels.size() <= 3;
  for (size_t l = 0; valid && l < fields.levels.size(); ++l)
    valid = fields.levels[l] >= 1 && fields.levels[l] <= 5 &&
            (l == 0 || fields.levels[l] == fields.levels[l - 1] - 1);
  if (!valid) throwInputError("{}: corrupt volumetric_opacity asset (header)", folder);
  mModel = {};
  mModel.compression = parseCompression(fields.compression);
  mModel.cameraDirections = fields.cameraDirections;
  mModel.cameraRight = fields.cameraRight;
  mModel.cameraUp = fields.cameraUp;
  mModel.tiles = asset.readBlobAs<uint8_t>("tiles_rgba.bin");
  const size_t tileBytes = size_t(fields.texels) * fields.texels * 4;
  const size_t tiles = mModel.tiles.size() / tileBytes;
  valid = mModel.tiles.size() == tiles * tileBytes;
  for (size_t l = 0; l < fields.levels.size(); ++l) {
    VolumetricLevel level;
    OpacityGrid& grid = level.grid;
    grid.setLattice(fields.root, fields.levels[l]);
    grid.nonEmptyPerLevel = fields.cellsPerLevel;
    grid.cells = asset.readBlobAs<glm::ivec3>(fmt::format("cells_{}.bin", l));
    grid.transparency = asset.readBlobAs<float>(fmt::format("transparency_{}.bin", l));
    level.table = asset.readBlobAs<uint32_t>(fmt::format("tile_table_{}.bin", l));
    // Every index the shaders follow is checked here, so a corrupt asset cannot read past a
    // buffer.
    valid = valid && grid.transparency.size() == grid.cells.size() &&
            level.table.size() == tableStride(views) * grid.cells.size();
    for (const glm::ivec3& c : grid.cells)
      valid = valid && glm::all(glm::greaterThanEqual(c, glm::ivec3(0))) &&
              glm::all(glm::lessThan(c, glm::ivec3(grid.side)));
    for (size_t c = 0; valid && c < grid.cells.size(); ++c)
      valid = uint64_t(level.table[c * tableStride(views)]) + tilesClaimed(level.table, views, c) <=
              tiles;
    if (!valid) throwInputError("{}: corrupt volumetric_opacity asset (level {})", folder, l);
    grid.rebuildLattice();
    buildOrders(level);
    mModel.levels.push_back(std::move(level));
  }
  buildAtlas(mModel, fields.texels, kMaxPageSize);
  asset.finishReading();
}

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
