// Volumetric opacity reconstruction (Reche-Martinez et al. 2004): the estimation of §5 on
// synthetic views whose alphas follow the paper's absorption model exactly, the Appendix A
// weights against brute-force sampling, texel selection and packing of §6.
#include <gtest/gtest.h>

#include <set>

#include "common/random.h"
#include "methods/volumetric_opacity/opacity_grid.h"
#include "methods/volumetric_opacity/opacity_solver.h"
#include "methods/volumetric_opacity/view_textures.h"
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

TEST(VolumetricTextures, EveryBillboardHoldsAtMostItsShareOfTexels) {
  const std::vector<glm::ivec3> cells = {{0, 1, 1}, {1, 1, 1}, {2, 1, 1}, {1, 2, 1}};
  const OpacityGrid truth = gridWith(1, cells, {0.5f, 0.3f, 0.8f, 0.6f});
  std::vector<CapturedView> captured = {syntheticView(truth, lookingAt({9, 1, 2}), 64),
                                        syntheticView(truth, lookingAt({1, 2, 9}), 64)};
  const auto views = prepareViews(captured, 0.02f);
  const ViewTextures textures = generateViewTextures(truth, views, {4, true, 2});
  ASSERT_EQ(textures.tile.size(), 2u * cells.size());
  ASSERT_GT(textures.tileCount(), 0u);
  for (size_t v = 0; v < 2; ++v) {
    for (size_t c = 0; c < cells.size(); ++c) {
      const uint32_t tile = textures.tile[v * cells.size() + c];
      if (tile == kNoTile) continue;
      int opaque = 0;
      for (int t = 0; t < 16; ++t) opaque += textures.alpha[tile * 16 + t] > 0;
      EXPECT_LE(opaque, int((1.0f - truth.transparency[c]) * 16.0f))
          << "view " << v << " cell " << c;
      EXPECT_GT(opaque, 0);
    }
  }
}

TEST(VolumetricTextures, PackingNeverOverlapsAlphasAndKeepsEveryColour) {
  ViewTextures textures;
  textures.texels = 4;
  textures.views = 1;
  textures.cells = 300;
  Random random(9, 2);
  for (int i = 0; i < textures.cells; ++i) {
    textures.tile.push_back(uint32_t(i));
    for (int t = 0; t < 16; ++t) {
      const bool opaque = random.uniform(0.0f, 1.0f) < 0.35f;
      textures.alpha.push_back(opaque ? uint8_t(1 + random.nextUint() % 255) : 0);
      for (int c = 0; c < 3; ++c) textures.rgb.push_back(uint8_t(random.nextUint() % 256));
    }
  }
  const PackedTextures packed = packTextures(textures);
  ASSERT_EQ(packed.slotOfTile.size(), 300u);
  EXPECT_LT(packed.slotCount(), 300u) << "some textures share a slot";
  std::map<uint32_t, std::vector<size_t>> tilesOfSlot;
  for (size_t tile = 0; tile < 300; ++tile) tilesOfSlot[packed.slotOfTile[tile]].push_back(tile);
  for (const auto& [slot, tiles] : tilesOfSlot) {
    ASSERT_LE(tiles.size(), 2u);
    for (int t = 0; t < 16; ++t) {
      int owners = 0;
      for (size_t tile : tiles) owners += textures.alpha[tile * 16 + t] > 0;
      EXPECT_LE(owners, 1) << "slot " << slot << " texel " << t;
      for (size_t tile : tiles) {
        if (textures.alpha[tile * 16 + t] == 0) continue;
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(packed.slotRgb[(slot * 16 + t) * 3 + c], textures.rgb[(tile * 16 + t) * 3 + c]);
      }
    }
  }
  EXPECT_EQ(packed.texelBytes(), 300u * 16 + packed.slotCount() * 48);
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

}  // namespace
}  // namespace canopy
