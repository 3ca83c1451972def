// Volumetric opacity reconstruction (Reche-Martinez et al. 2004): the estimation of §5 on
// synthetic views whose alphas follow the paper's absorption model exactly, the Appendix A
// weights against brute-force sampling, texel selection and packing of §6.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>

#include "common/random.h"
#include "methods/volumetric_opacity/opacity_grid.h"
#include "methods/volumetric_opacity/opacity_solver.h"
#include "methods/volumetric_opacity/view_textures.h"
#include "methods/volumetric_opacity/volumetric_levels.h"
#include "test_support.h"

namespace canopy {
namespace {

// A grid over [-1.5, 1.5]³ of the given level with the listed cells non-empty.
OpacityGrid gridWith(int level, const std::vector<glm::ivec3>& cells,
                     const std::vector<float>& transparency) {
  OpacityGrid grid;
  grid.root.min = glm::vec3(-1.5f);
  grid.root.max = glm::vec3(1.5f);
  grid.level = level;
  grid.side = level == 0 ? 1 : (level == 1 ? 3 : 9);
  grid.cellSize = 3.0f / float(grid.side);
  grid.cells = cells;
  grid.transparency = transparency;
  grid.rebuildLattice();
  return grid;
}

Camera lookingAt(glm::vec3 position, float fovY = 30.0f) {
  Camera camera;
  camera.position = position;
  camera.target = glm::vec3(0.0f);
  camera.up = std::abs(position.y) > 0.9f * glm::length(position) ? glm::vec3(0, 0, -1)
                                                                  : glm::vec3(0, 1, 0);
  camera.fovYDegrees = fovY;
  return camera;
}

// An image whose alpha at each pixel is 1 − Π t over the cells the pixel's ray crosses in
// `truth`: the absorption model of Eq. 4–8, so an exact solution exists.
CapturedView syntheticView(const OpacityGrid& truth, const Camera& camera, int size) {
  CapturedView view{camera, ImageRgbaF(size, size), "synthetic"};
  const PixelCamera pixels(camera, size, size);
  std::vector<RaySegment> segments;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      float t = 1.0f;
      if (traceRay(truth, pixels, float(x) + 0.5f, float(y) + 0.5f, segments))
        for (const RaySegment& s : segments) t *= truth.transparency[s.cell];
      float* p = view.image.at(x, y);
      p[0] = p[1] = p[2] = 0.5f * (1.0f - t);
      p[3] = 1.0f - t;
    }
  }
  return view;
}

// Two views of a grid: one along x (rays cross both cells on the x axis), one along z.
std::vector<CapturedView> alongAndAcross(const OpacityGrid& truth) {
  return {syntheticView(truth, lookingAt({12, 0, 0}, 20.0f), 64),
          syntheticView(truth, lookingAt({0, 0, 12}, 20.0f), 64)};
}

TEST(VolumetricEstimation, OneCellSeenBySeveralRaysConvergesToTheExactTransparency) {
  const OpacityGrid truth = gridWith(1, {{1, 1, 1}}, {0.4f});
  std::vector<CapturedView> captured;
  for (glm::vec3 p : {glm::vec3(8, 0, 0), glm::vec3(0, 0, 8), glm::vec3(-6, 3, 2)})
    captured.push_back(syntheticView(truth, lookingAt(p), 48));
  const auto views = prepareViews(captured, 0.02f);
  // Start from a wrong value; cutoff 1 so nothing is removed.
  OpacityGrid grid = gridWith(1, {{1, 1, 1}}, {0.9f});
  const SolverResult result = solveByProjection(grid, views, {50, 1e-6f, 1.0f, 1});
  EXPECT_TRUE(result.converged);
  EXPECT_NEAR(grid.transparency[0], 0.4f, 1e-4f);
  EXPECT_GT(result.rays, 100);
  EXPECT_LT(result.finalRmsTransparency, 1e-4);
}

TEST(VolumetricEstimation, TwoCellsAlongRaysOfTwoViewsAreBothRecovered) {
  // Two cells on the x axis: the view along x sees only their product, the view along z sees
  // each alone; together they determine both.
  const std::vector<glm::ivec3> cells = {{0, 1, 1}, {2, 1, 1}};
  const OpacityGrid truth = gridWith(1, cells, {0.3f, 0.7f});
  const std::vector<CapturedView> captured = alongAndAcross(truth);
  const auto views = prepareViews(captured, 0.02f);
  OpacityGrid grid = gridWith(1, cells, {0.6f, 0.6f});
  const SolverResult result = solveByProjection(grid, views, {500, 1e-6f, 1.0f, 1});
  EXPECT_NEAR(grid.transparency[0], 0.3f, 0.01f);
  EXPECT_NEAR(grid.transparency[1], 0.7f, 0.01f);
  ASSERT_GE(result.iterations.size(), 2u);
  EXPECT_LT(result.iterations.back().rmsTransparency, result.iterations.front().rmsTransparency);
}

TEST(VolumetricEstimation, CeresFitsTheSameTwoCells) {
  const std::vector<glm::ivec3> cells = {{0, 1, 1}, {2, 1, 1}};
  const OpacityGrid truth = gridWith(1, cells, {0.3f, 0.7f});
  const std::vector<CapturedView> captured = alongAndAcross(truth);
  const auto views = prepareViews(captured, 0.02f);
  OpacityGrid grid = gridWith(1, cells, {0.6f, 0.6f});
  const SolverResult result = solveWithCeres(grid, views, {50, 1e-6f, 1.0f, 1});
  EXPECT_NEAR(grid.transparency[0], 0.3f, 0.01f);
  EXPECT_NEAR(grid.transparency[1], 0.7f, 0.01f);
  EXPECT_LT(result.finalRmsTransparency, 1e-3);
}

TEST(VolumetricEstimation, CutoffEmptiesCellsAboveTheThreshold) {
  const std::vector<glm::ivec3> cells = {{0, 1, 1}, {2, 1, 1}};
  const OpacityGrid truth = gridWith(1, cells, {0.3f, 0.97f});
  const std::vector<CapturedView> captured = alongAndAcross(truth);
  const auto views = prepareViews(captured, 0.02f);
  OpacityGrid grid = gridWith(1, cells, {0.6f, 0.6f});
  solveByProjection(grid, views, {100, 1e-5f, 0.94f, 1});
  EXPECT_NEAR(grid.transparency[0], 0.3f, 0.02f);
  EXPECT_EQ(grid.transparency[1], 1.0f) << "above the 0.94 cutoff the cell becomes empty";
}

TEST(VolumetricEstimation, AppendixAWeightsMatchTheShareOfEachCellInThePixelsPyramid) {
  // All 27 cells of a level-1 grid; an 8×8 camera whose pixel (4, 3) pyramid stays inside the
  // central column of cells, so the weight is the pyramid's volume in each cell over the cell's.
  std::vector<glm::ivec3> all;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x) all.push_back({x, y, z});
  const OpacityGrid grid = gridWith(1, all, std::vector<float>(27, 0.5f));
  const Camera camera = lookingAt({0, 0, 10}, 20.0f);
  const PixelCamera pixels(camera, 8, 8);
  std::vector<RaySegment> segments;
  ASSERT_TRUE(traceRay(grid, pixels, 4.5f, 3.5f, segments));
  ASSERT_EQ(segments.size(), 3u);
  Random random(5, 1);
  for (const RaySegment& segment : segments) {
    const Aabb box = grid.cellBox(size_t(segment.cell));
    const int samples = 400000;
    int inside = 0;
    for (int i = 0; i < samples; ++i) {
      const glm::vec3 p(random.uniform(box.min.x, box.max.x), random.uniform(box.min.y, box.max.y),
                        random.uniform(box.min.z, box.max.z));
      const glm::vec2 q = pixels.project(p);
      inside += q.x >= 4.0f && q.x < 5.0f && q.y >= 3.0f && q.y < 4.0f;
    }
    const double share = double(inside) / samples;
    // Monte Carlo standard error ≈ sqrt(p(1−p)/N) ≈ 6·10⁻⁴ for p ≈ 0.19: 4 sigma.
    EXPECT_NEAR(segment.weight, share, 2.5e-3) << "cell " << segment.cell;
    EXPECT_GT(share, 0.05);
  }
  // Front to back.
  EXPECT_EQ(grid.cells[size_t(segments[0].cell)].z, 2);
  EXPECT_EQ(grid.cells[size_t(segments[2].cell)].z, 0);
}

TEST(VolumetricGrid, EmptyCellsAreNotSubdividedAndTheHullContainsTheObject) {
  // The truth occupies one level-2 cell; views of it carve everything else.
  const OpacityGrid truth = gridWith(2, {{4, 4, 4}}, {0.2f});
  std::vector<CapturedView> captured;
  for (glm::vec3 p :
       {glm::vec3(9, 0, 0), glm::vec3(0, 0, 9), glm::vec3(0, 9, 0.1f), glm::vec3(6, 2, 6)})
    captured.push_back(syntheticView(truth, lookingAt(p, 35.0f), 96));
  const auto views = prepareViews(captured, 0.02f);
  Aabb cube;
  cube.min = glm::vec3(-1.5f);
  cube.max = glm::vec3(1.5f);
  const OpacityGrid grid = buildOpacityGrid(cube, 2, views, 0.02f);
  ASSERT_EQ(grid.nonEmptyPerLevel.size(), 3u);
  EXPECT_EQ(grid.nonEmptyPerLevel[0], 1);
  EXPECT_EQ(grid.nonEmptyPerLevel[1], 1) << "only the central level-1 cell is kept";
  EXPECT_LE(grid.nonEmptyPerLevel[2], 27) << "children of the kept cell only";
  EXPECT_GE(grid.cellAt({4, 4, 4}), 0) << "the occupied cell survives";
  // §5 initialisation: 1 − min over views of the mean alpha in the cell's projected rectangle,
  // which also holds background pixels: never more opaque than the truth (0.2), but opaque.
  const float initial = grid.transparency[size_t(grid.cellAt({4, 4, 4}))];
  EXPECT_GE(initial, 0.2f - 1e-3f);
  EXPECT_LT(initial, 0.7f);
}

TEST(VolumetricTextures, SelectionKeepsTheFloorOfAlphaTimesTexelsOldestFirst) {
  std::vector<uint16_t> ages(64, 0);
  std::vector<float> importance(64);
  for (int i = 0; i < 64; ++i) importance[i] = float(i);
  ages[3] = 2;
  const std::vector<int> selected = selectTexels(ages, importance, 0.3f);
  EXPECT_EQ(selected.size(), 44u);  // ⌊0.7 · 64⌋
  EXPECT_EQ(selected[0], 3) << "oldest first";
  EXPECT_EQ(selected[1], 63) << "then by importance";
  EXPECT_EQ(selectTexels(ages, importance, 1.0f).size(), 0u);
  EXPECT_EQ(selectTexels(ages, importance, 0.0f).size(), 64u);
}

TEST(VolumetricTextures, PaperSelectionHoldsAtMostEachCellsShareOfTexels) {
  const std::vector<glm::ivec3> cells = {{0, 1, 1}, {1, 1, 1}, {2, 1, 1}, {1, 2, 1}};
  const OpacityGrid truth = gridWith(1, cells, {0.5f, 0.3f, 0.8f, 0.6f});
  std::vector<CapturedView> captured = {syntheticView(truth, lookingAt({9, 1, 2}), 64),
                                        syntheticView(truth, lookingAt({1, 2, 9}), 64)};
  const auto views = prepareViews(captured, 0.02f);
  TextureSettings settings;
  settings.texels = 4;
  settings.selection = TexelSelection::kPaper;
  const ViewTextures textures = generateViewTextures(truth, views, settings);
  ASSERT_EQ(textures.tile.size(), 2u * cells.size());
  ASSERT_GT(textures.tileCount(), 0u);
  for (size_t v = 0; v < 2; ++v) {
    for (size_t c = 0; c < cells.size(); ++c) {
      const uint32_t tile = textures.tile[v * cells.size() + c];
      if (tile == kNoTile) continue;
      int opaque = 0;
      for (int t = 0; t < 16; ++t) opaque += textures.rgba[(tile * 16 + t) * 4 + 3] > 0;
      EXPECT_LE(opaque, int((1.0f - truth.transparency[c]) * 16.0f))
          << "view " << v << " cell " << c;
      EXPECT_GT(opaque, 0);
    }
  }
}

// A volume of 40 random cells of a level-2 grid with random transparencies.
OpacityGrid randomVolume(uint64_t seed) {
  Random random(seed, 1);
  std::set<std::tuple<int, int, int>> chosen;
  while (chosen.size() < 40)
    chosen.insert({2 + int(random.nextUint() % 5), 2 + int(random.nextUint() % 5),
                   2 + int(random.nextUint() % 5)});
  std::vector<glm::ivec3> cells;
  std::vector<float> transparency;
  for (const auto& [z, y, x] : chosen) {  // lattice order (z, y, x), as the grid keeps it
    cells.emplace_back(x, y, z);
    transparency.push_back(random.uniform(0.2f, 0.9f));
  }
  return gridWith(2, cells, transparency);
}

// Mean |composited alpha − α_p| over the pixels of `view` that either covers: the view's
// billboards composited front to back at every pixel centre, each texel looked up nearest.
double compositingError(const OpacityGrid& grid, const ViewTextures& textures,
                        const OpacityView& view, size_t v) {
  const PixelCamera& cam = view.camera;
  const glm::vec2 half = billboardHalfExtents(grid.cellSize, cam.right(), cam.up());
  std::vector<size_t> order(grid.cells.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return cam.depth(grid.cellCenter(a)) < cam.depth(grid.cellCenter(b));
  });
  const int m = textures.texels;
  double error = 0.0;
  int pixels = 0;
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x) {
      double transmitted = 1.0;
      for (size_t c : order) {
        const uint32_t tile = textures.tile[v * grid.cells.size() + c];
        if (tile == kNoTile) continue;
        const glm::vec3 center = grid.cellCenter(c);
        const glm::vec2 h = half * cam.focalPixels() / cam.depth(center);
        const glm::vec2 unit =
            (glm::vec2(x + 0.5f, y + 0.5f) - (cam.project(center) - h)) / (2.0f * h);
        if (glm::any(glm::lessThan(unit, glm::vec2(0))) ||
            glm::any(glm::greaterThanEqual(unit, glm::vec2(1))))
          continue;
        const int a = int(unit.x * float(m)), b = int(unit.y * float(m));
        transmitted *=
            1.0 - textures.rgba[(size_t(tile) * m * m + size_t(b) * m + a) * 4 + 3] / 255.0;
      }
      const double alpha = view.image->at(x, y)[3];
      if (alpha <= 0.0 && transmitted >= 1.0) continue;
      error += std::abs((1.0 - transmitted) - alpha);
      ++pixels;
    }
  }
  return pixels ? error / pixels : 0.0;
}

TEST(VolumetricTextures, PartitionCompositesBackToEachTrainingViewsAlpha) {
  const OpacityGrid truth = randomVolume(5);
  std::vector<CapturedView> captured = {syntheticView(truth, lookingAt({12, 1, 3}), 128),
                                        syntheticView(truth, lookingAt({-2, 9, 8}), 128)};
  const auto views = prepareViews(captured, 0.02f);
  TextureSettings partition;
  partition.texels = 8;
  partition.hiddenCutoff = 0.0f;
  TextureSettings paper = partition;
  paper.selection = TexelSelection::kPaper;
  const ViewTextures shared = generateViewTextures(truth, views, partition);
  const ViewTextures selected = generateViewTextures(truth, views, paper);
  for (size_t v = 0; v < views.size(); ++v) {
    const double partitionError = compositingError(truth, shared, views[v], v);
    const double paperError = compositingError(truth, selected, views[v], v);
    // Texels are about a pixel wide, so only pixels where a billboard's texel centre falls in
    // the neighbouring pixel differ; 8-bit alpha adds 1/510 at most per billboard.
    EXPECT_LT(partitionError, 0.03) << "view " << v;
    EXPECT_LT(partitionError, 0.5 * paperError) << "view " << v;
  }
}

TEST(VolumetricTextures, HiddenTexturesAreDroppedOnlyBehindOpaqueCells) {
  // Three cells in a row along x, seen along x: the front one nearly opaque.
  const OpacityGrid truth = gridWith(1, {{0, 1, 1}, {1, 1, 1}, {2, 1, 1}}, {0.5f, 0.6f, 0.01f});
  std::vector<CapturedView> captured = {syntheticView(truth, lookingAt({12, 0, 0}, 20.0f), 64)};
  const auto views = prepareViews(captured, 0.02f);
  TextureSettings settings;
  settings.texels = 4;
  settings.hiddenCutoff = 0.05f;
  const ViewTextures textures = generateViewTextures(truth, views, settings);
  EXPECT_NE(textures.tile[2], kNoTile) << "the front cell (x = 2, nearest the camera) is kept";
  EXPECT_EQ(textures.tile[0], kNoTile) << "the back cell adds under 0.5 · 0.01 behind it";
  EXPECT_EQ(textures.hiddenTiles, 2u);
}

TEST(VolumetricGrid, CoarserLevelKeepsTheChildrensOpticalDepthPerColumn) {
  // Three children of one parent in a column and one alone in another parent.
  const OpacityGrid fine =
      gridWith(2, {{0, 0, 0}, {0, 0, 1}, {0, 0, 2}, {8, 8, 8}}, {0.5f, 0.5f, 0.5f, 0.2f});
  const OpacityGrid coarse = coarsenGrid(fine, 1e-3f);
  ASSERT_EQ(coarse.level, 1);
  ASSERT_EQ(coarse.cells.size(), 2u);
  EXPECT_EQ(coarse.cells[0], glm::ivec3(0, 0, 0));
  EXPECT_EQ(coarse.cells[1], glm::ivec3(2, 2, 2));
  EXPECT_NEAR(coarse.transparency[0], std::pow(0.125f, 1.0f / 9.0f), 1e-5f);
  EXPECT_NEAR(coarse.transparency[1], std::pow(0.2f, 1.0f / 9.0f), 1e-5f);
  EXPECT_FLOAT_EQ(coarse.cellSize, 3.0f * fine.cellSize);
}

TEST(VolumetricTextures, CompactTableFindsEveryCellsTileOfEveryView) {
  // 40 views (two mask words), 5 cells; tiles numbered cell by cell in view order.
  const size_t views = 40, cells = 5;
  std::vector<uint32_t> full(views * cells, kNoTile);
  uint32_t next = 0;
  for (size_t c = 0; c < cells; ++c)
    for (size_t v = 0; v < views; ++v)
      if ((v * 7 + c * 3) % 5 < 2 || (c == 4 && v == 39)) full[v * cells + c] = next++;
  const std::vector<uint32_t> table = compactTileTable(full, views, cells, 100);
  ASSERT_EQ(table.size(), cells * 3);
  size_t claimed = 0;
  for (size_t c = 0; c < cells; ++c) {
    claimed += tilesClaimed(table, views, c);
    for (size_t v = 0; v < views; ++v) {
      const uint32_t expected =
          full[v * cells + c] == kNoTile ? kNoTile : full[v * cells + c] + 100;
      ASSERT_EQ(tileOf(table, views, v, c), expected) << "view " << v << " cell " << c;
    }
  }
  EXPECT_EQ(claimed, size_t(next));
}

TEST(VolumetricTextures, AtlasPagesHoldEveryTileWhereTheShadersLookForIt) {
  const int m = 8, tiles = 70;
  std::vector<uint8_t> rgba(size_t(tiles) * m * m * 4);
  for (size_t i = 0; i < rgba.size(); ++i) rgba[i] = uint8_t((i * 7 + i / 256) % 251);
  const TileAtlas atlas = layOutTiles(rgba, m, 32);  // 16 tiles a page
  EXPECT_EQ(atlas.pageSize, 32);
  ASSERT_EQ(atlas.pages.size(), 5u);
  for (int t = 0; t < tiles; ++t) {
    const int slot = t % atlas.tilesPerPage();
    const ImageRgba8& page = atlas.pages[size_t(t / atlas.tilesPerPage())];
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a)
        ASSERT_EQ(
            std::memcmp(page.at(slot % atlas.tilesPerRow * m + a, slot / atlas.tilesPerRow * m + b),
                        &rgba[(size_t(t) * m * m + size_t(b) * m + a) * 4], 4),
            0)
            << "tile " << t;
  }
  EXPECT_EQ(layOutTiles(rgba, m, 4096).pageSize, 128) << "the smallest page holding them all";
}

TEST(VolumetricOpacity, RejectsParametersOutOfRangeNamingTheKey) {
  test::expectParameterErrorsNameTheKey("volumetric_opacity", {{"level", 0},
                                                               {"level", 6},
                                                               {"texels", 16},
                                                               {"cutoff", 1.5},
                                                               {"solver", "gradient"},
                                                               {"views", 1},
                                                               {"ray_stride", 0}});
}

// The orders as uploaded: 13 stored directions (the other 13 walked backwards) in 16-bit cells
// still give, for every one of the 26 directions, every cell once, farthest from a viewer along
// that direction first; a level of more than 65,536 cells keeps 32-bit cells.
TEST(VolumetricOrders, PackedOrdersWalkEveryDirectionBackToFront) {
  std::vector<VolumetricLevel> levels(2);
  levels[0].grid = randomVolume(3);
  levels[1].grid = randomVolume(4);
  for (VolumetricLevel& level : levels) buildOrders(level);
  const PackedOrders packed = packOrders(levels);
  EXPECT_TRUE(packed.sixteenBit);
  size_t full = 0;
  for (const VolumetricLevel& level : levels) full += level.orders.size() * 4;
  EXPECT_LE(packed.words.size() * 4, full / 4 + 4) << "a quarter of the 26 32-bit orders";
  const std::vector<glm::vec3> directions = orderDirections();
  ASSERT_EQ(directions.size(), size_t(kOrderDirections));
  for (size_t l = 0; l < levels.size(); ++l) {
    const OpacityGrid& grid = levels[l].grid;
    const size_t n = grid.cells.size();
    for (size_t d = 0; d < directions.size(); ++d) {
      const auto [first, reversed] = packed.lookup(l, d, n);
      std::set<uint32_t> seen;
      float previous = -std::numeric_limits<float>::infinity();
      for (size_t position = 0; position < n; ++position) {
        const uint32_t cell = packed.cellAt(first, reversed, n, position);
        ASSERT_LT(cell, n);
        seen.insert(cell);
        const float key = glm::dot(grid.cellCenter(cell), directions[d]);
        EXPECT_GE(key, previous - 1e-5f) << "level " << l << " direction " << d;
        previous = key;
      }
      EXPECT_EQ(seen.size(), n) << "every cell once";
    }
  }
  VolumetricLevel large;
  large.grid.cells.resize(65537);
  large.orders.assign(size_t(kOrderDirections) * 65537, 65536u);
  const PackedOrders wide = packOrders({large});
  EXPECT_FALSE(wide.sixteenBit);
  EXPECT_EQ(wide.cellAt(wide.lookup(0, 20, 65537).first, true, 65537, 7), 65536u);
}

}  // namespace
}  // namespace canopy
