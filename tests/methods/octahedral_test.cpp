#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "common/random.h"
#include "methods/method.h"
#include "methods/octahedral/octahedral_capture.h"
#include "methods/octahedral/octahedral_mapping.h"
#include "test_support.h"

namespace canopy {
namespace {

glm::vec3 randomDirection(Random& random) {
  const float z = random.uniform(-1.0f, 1.0f), phi = random.uniform(0.0f, 6.2831853f);
  const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {s * std::cos(phi), z, s * std::sin(phi)};
}

TEST(OctahedralMapping, DirectionsRoundTripThroughTheSquare) {
  Random random(5, 11);
  for (bool hemisphere : {false, true}) {
    const OctahedralGrid grid{16, hemisphere};
    for (int i = 0; i < 2000; ++i) {
      glm::vec3 d = randomDirection(random);
      if (hemisphere) d.y = std::abs(d.y);
      const glm::vec2 p = grid.encode(d);
      ASSERT_LE(std::abs(p.x), 1.0f + 1e-5f);
      ASSERT_LE(std::abs(p.y), 1.0f + 1e-5f);
      const glm::vec3 back = grid.decode(p);
      // 1e-4 rad: float round-off of the L1 normalisation, far below a frame's spacing.
      EXPECT_GT(glm::dot(back, d), 1.0f - 1e-6f) << "hemisphere " << hemisphere;
    }
  }
}

TEST(OctahedralMapping, SquarePointsRoundTripThroughDirections) {
  for (bool hemisphere : {false, true}) {
    const OctahedralGrid grid{16, hemisphere};
    for (int y = 0; y <= 20; ++y) {
      for (int x = 0; x <= 20; ++x) {
        const glm::vec2 p(x / 10.0f - 1.0f, y / 10.0f - 1.0f);
        const glm::vec2 again = grid.encode(grid.decode(p));
        // The full octahedron's square edges fold onto each other: compare directions there.
        EXPECT_GT(glm::dot(grid.decode(again), grid.decode(p)), 1.0f - 1e-6f);
        if (std::abs(p.x) < 0.999f && std::abs(p.y) < 0.999f) {
          EXPECT_NEAR(again.x, p.x, 1e-5f);
          EXPECT_NEAR(again.y, p.y, 1e-5f);
        }
      }
    }
  }
}

TEST(OctahedralMapping, ThreeFramesAroundEachViewWithWeightsSummingToOne) {
  Random random(9, 3);
  for (bool hemisphere : {false, true}) {
    const OctahedralGrid grid{12, hemisphere};
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 d = randomDirection(random);
      const FrameBlend blend = blendFrames(grid, d);
      EXPECT_NEAR(blend.weights.x + blend.weights.y + blend.weights.z, 1.0f, 1e-5f);
      float nearest = -1.0f;
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(blend.weights[k], -1e-6f);
        ASSERT_GE(blend.frames[k].x, 0);
        ASSERT_LT(blend.frames[k].x, grid.frames);
        ASSERT_GE(blend.frames[k].y, 0);
        ASSERT_LT(blend.frames[k].y, grid.frames);
        nearest = std::max(nearest,
                           glm::dot(grid.frameDirection(blend.frames[k]), grid.clampDirection(d)));
      }
      // The triangle's frames are neighbours of the view: within about two grid spacings
      // (90° / (N − 1) on the hemisphere's square, 180° / (N − 1) on the full octahedron).
      const float spacing = (hemisphere ? 90.0f : 180.0f) / float(grid.frames - 1);
      EXPECT_GT(nearest, std::cos(2.0f * spacing * 3.14159265f / 180.0f));
    }
  }
}

TEST(OctahedralMapping, AFramesOwnDirectionSelectsItAlone) {
  const OctahedralGrid grid{8, true};
  for (int j = 0; j < grid.frames; ++j) {
    for (int i = 0; i < grid.frames; ++i) {
      const FrameBlend blend = blendFrames(grid, grid.frameDirection({i, j}));
      float weight = 0.0f;
      for (int k = 0; k < 3; ++k)
        if (blend.frames[k] == glm::ivec2(i, j)) weight += blend.weights[k];
      EXPECT_NEAR(weight, 1.0f, 1e-4f) << "frame " << i << "," << j;
    }
  }
}

TEST(OctahedralMapping, HemisphereClampsViewsFromBelowOntoTheHorizon) {
  const OctahedralGrid grid{16, true};
  const glm::vec3 below = glm::normalize(glm::vec3(0.6f, -0.5f, 0.2f));
  const glm::vec3 horizon = glm::normalize(glm::vec3(0.6f, 0.0f, 0.2f));
  EXPECT_NEAR(glm::dot(grid.clampDirection(below), horizon), 1.0f, 1e-6f);
  const glm::vec2 a = grid.encode(below), b = grid.encode(horizon);
  EXPECT_NEAR(a.x, b.x, 1e-6f);
  EXPECT_NEAR(a.y, b.y, 1e-6f);
  // The horizon is the square's boundary; straight up is its centre.
  EXPECT_NEAR(std::max(std::abs(b.x), std::abs(b.y)), 1.0f, 1e-5f);
  const glm::vec2 top = grid.encode({0.0f, 1.0f, 0.0f});
  EXPECT_NEAR(top.x, 0.0f, 1e-6f);
  EXPECT_NEAR(top.y, 0.0f, 1e-6f);
  // Straight down has no horizontal part: it clamps to a horizon direction, not to NaN.
  const glm::vec3 down = grid.clampDirection({0.0f, -1.0f, 0.0f});
  EXPECT_NEAR(glm::length(down), 1.0f, 1e-6f);
  EXPECT_NEAR(down.y, 0.0f, 1e-6f);
}

TEST(OctahedralMapping, FrameAxesAreOrthonormalAndUpright) {
  Random random(2, 8);
  for (int i = 0; i < 500; ++i) {
    const glm::vec3 d = randomDirection(random);
    const FrameAxes axes = frameAxes(d);
    EXPECT_NEAR(glm::length(axes.right), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::length(axes.up), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(axes.right, d), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(axes.up, d), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(axes.right, axes.up), 0.0f, 1e-5f);
    if (std::abs(d.y) < 0.99f) {
      EXPECT_GE(axes.up.y, 0.0f);  // world up projects upwards
    }
    // right × up points at the camera: a right-handed image seen from the camera.
    EXPECT_GT(glm::dot(glm::cross(axes.right, axes.up), d), 0.99f);
  }
}

// A frame captured straight from the side shows the tree where an orthographic projection puts
// it: coverage inside the trunk's column at the bottom, none outside the bounding sphere.
TEST(OctahedralCapture, FramesHoldTheTreeWithCoverageDepthAndNormals) {
  const Tree tree = test::smallTree(600, 3);
  OctahedralCaptureSettings settings;
  settings.grid = {4, true};
  settings.cellTexels = 48;
  settings.padding = 4;
  const OctahedralFrames frames = captureOctahedralFrames(tree, settings);
  ASSERT_EQ(frames.color.width, 4 * 48);
  EXPECT_GT(frames.coveredFraction, 0.02);
  EXPECT_LT(frames.coveredFraction, 0.9);
  const int inner = settings.cellTexels - 2 * settings.padding;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      const glm::vec3 toCamera = settings.grid.frameDirection({i, j});
      int covered = 0;
      for (int y = 0; y < 48; ++y) {
        for (int x = 0; x < 48; ++x) {
          const int ax = i * 48 + x, ay = j * 48 + y;
          const uint8_t* c = frames.color.at(ax, ay);
          const bool inside = x >= 4 && y >= 4 && x < 44 && y < 44;
          if (!inside) {
            EXPECT_EQ(c[3], 0) << "padding texel " << ax << "," << ay;
            continue;
          }
          // Texel centre in units of the sphere radius: nothing covered outside the disc.
          const float u = ((x - 4) + 0.5f) / inner * 2.0f - 1.0f;
          const float v = ((y - 4) + 0.5f) / inner * 2.0f - 1.0f;
          if (u * u + v * v > 1.1f) {
            EXPECT_EQ(c[3], 0);
          }
          if (c[3] == 0) continue;
          ++covered;
          const uint8_t* n = frames.normalDepth.at(ax, ay);
          const glm::vec3 normal = glm::vec3(n[0], n[1], n[2]) / 255.0f * 2.0f - 1.0f;
          // Normals face the frame's camera (8-bit quantisation and averaging: a small margin).
          EXPECT_GT(glm::dot(normal, toCamera), -0.05f);
        }
      }
      EXPECT_GT(covered, 20) << "frame " << i << "," << j;
    }
  }
}

// The covered rectangle of a frame with texels (2, 5) and (4, 6) covered: texel t spans
// [t, t + 1] / inner · 2 − 1, grown by the margin and clamped to the frame.
TEST(OctahedralCapture, FrameRectanglesBoundTheCoveredTexels) {
  const int frames = 2, cell = 12, padding = 2, inner = cell - 2 * padding;
  ImageRgba8 atlas(frames * cell, frames * cell);
  const auto cover = [&](int frameX, int frameY, int x, int y) {
    atlas.pixels[(size_t(frameY * cell + padding + y) * atlas.width + frameX * cell + padding + x) *
                     4 +
                 3] = 200;
  };
  cover(1, 0, 2, 5);
  cover(1, 0, 4, 6);
  const std::vector<glm::vec4> rects = frameCoverageRects(atlas, frames, cell, padding, 1);
  ASSERT_EQ(rects.size(), 4u);
  const auto edge = [&](int t) { return std::clamp(float(t) / inner * 2.0f - 1.0f, -1.0f, 1.0f); };
  const glm::vec4 expected(edge(1), edge(4), edge(6), edge(8));
  for (int c = 0; c < 4; ++c) EXPECT_FLOAT_EQ(rects[1][c], expected[c]) << c;
  for (int f : {0, 2, 3}) EXPECT_GT(rects[f].x, rects[f].z) << "frame " << f << " is empty";
}

// Near the camera the impostor is the polygonal mesh, far away the impostor alone, and in the
// band between each pixel comes from one of the two (complementary dither ranges), the mesh's
// share growing with the tree's size in pixels.
TEST(OctahedralMeshFade, TheMeshReplacesTheImpostorNearTheCameraThroughADitheredBand) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = test::smallTree(300, 3);
  RenderSettings settings;
  settings.width = settings.height = 96;
  settings.supersample = 1;  // every output pixel is one fragment: from the mesh or the impostor
  settings.fovYDegrees = 30.0f;
  Harness harness(device, settings);
  const float radius = tree.boundingSphereRadius();
  const float focal = 48.0f / std::tan(15.0f * 3.14159265f / 180.0f);
  // The radius spans `pixels` output pixels from distance radius · focal / pixels.
  const auto cameraAt = [&](float pixels) {
    Camera camera;
    camera.target = tree.bounds.center();
    camera.position =
        camera.target + glm::vec3(0.3f, 0.2f, 1.0f) * (radius * focal / pixels / std::sqrt(1.13f));
    camera.fovYDegrees = settings.fovYDegrees;
    return camera;
  };
  const auto make = [&](const std::string& name, const nlohmann::json& params) {
    return test::bakeAndUpload(device, tree, name, params);
  };
  auto mesh = make("polygonal", nlohmann::json::object());
  auto impostor = make("octahedral", {{"atlas_size", 512}});
  auto fading =
      make("octahedral", {{"atlas_size", 512}, {"mesh_pixels", 40.0}, {"fade_band", 0.5}});
  const uint64_t leaves = tree.leaves.size();

  // Whole mesh at 60 px, impostor alone at 10 px: the same images as either method.
  for (const auto& [pixels, expected] : {std::pair{60.0f, mesh.get()}, {10.0f, impostor.get()}}) {
    const Camera camera = cameraAt(pixels);
    const ImageRgba8 image = harness.render(*fading, camera);
    EXPECT_EQ(image.pixels, harness.render(*expected, camera).pixels) << pixels << " px";
    harness.render(*fading, camera);
    EXPECT_EQ(fading->leafPolygonsDrawn(), expected == mesh.get() ? leaves : 0u);
    // States: mesh, fading, three frames, one frame (below blend_pixels, default 96).
    EXPECT_EQ(fading->instancesPerLevel(),
              (expected == mesh.get() ? std::vector<uint64_t>{1, 0, 0, 0}
                                      : std::vector<uint64_t>{0, 0, 0, 1}));
  }

  // At 30 px the mesh's share is (30 − 20) / 20 = 0.5: every pixel is the mesh's or the
  // impostor's, and about half of the pixels where they differ are the mesh's.
  const Camera camera = cameraAt(30.0f);
  const ImageRgba8 blend = harness.render(*fading, camera);
  EXPECT_EQ(fading->leafPolygonsDrawn(), leaves);
  EXPECT_EQ(fading->instancesPerLevel(), (std::vector<uint64_t>{0, 1, 0, 0}));
  const ImageRgba8 meshImage = harness.render(*mesh, camera);
  const ImageRgba8 impostorImage = harness.render(*impostor, camera);
  size_t fromMesh = 0, differing = 0, fromNeither = 0;
  for (size_t p = 0; p < blend.pixels.size(); p += 4) {
    const auto same = [&](const ImageRgba8& other) {
      return std::equal(blend.pixels.begin() + p, blend.pixels.begin() + p + 4,
                        other.pixels.begin() + p);
    };
    const bool mesh = same(meshImage), impostor = same(impostorImage);
    if (!mesh && !impostor) ++fromNeither;
    if (mesh != impostor) ++differing, fromMesh += mesh;
  }
  std::printf("fade band: %zu differing pixels, %zu from the mesh, %zu from neither\n", differing,
              fromMesh, fromNeither);
  ASSERT_GT(differing, 200u);
  // Neither: edge pixels where the other's depth test let a different surface through.
  EXPECT_LT(double(fromNeither) / differing, 0.1);
  // 0.5 ± 0.15: the 4×4 Bayer pattern keeps exactly half of its pixels; the rest is how the
  // differing pixels fall on the pattern.
  EXPECT_NEAR(double(fromMesh) / differing, 0.5, 0.15);

  // The mesh is saved with the impostor and loads back into the same band image; an asset
  // without it is bad input.
  test::TempDir dir;
  AssetFolder asset(dir.path());
  fading->save(asset);
  auto loaded = builtinMethods().find("octahedral").create(fading->effectiveParams(), "test");
  AssetFolder reader(dir.path());
  loaded->load(reader);
  {
    gl::Device::OwnerScope scope(device, "loaded");
    loaded->upload(device);
  }
  EXPECT_EQ(harness.render(*loaded, camera).pixels, blend.pixels);
  std::filesystem::remove_all(dir.path() / "mesh");
  auto broken = builtinMethods().find("octahedral").create(fading->effectiveParams(), "test");
  AssetFolder again(dir.path());
  EXPECT_THROW(broken->load(again), InputError);
}

TEST(Octahedral, BadParametersNameTheParameter) {
  test::expectParameterErrorsNameTheKey("octahedral", {{"frames", 1},
                                                       {"atlas_size", 10},
                                                       {"normal_depth_divisor", 3},
                                                       {"blend", "two"},
                                                       {"compression", "dxt1"},
                                                       {"parallax_steps", -1},
                                                       {"mesh_pixels", -1.0},
                                                       {"fade_band", 0.0},
                                                       {"blend_pixels", "far"}});
  // Frames too small for their padding: the message names atlas_size and what to change.
  try {
    builtinMethods().find("octahedral").create({{"atlas_size", 256}, {"frames", 32}}, "test");
    ADD_FAILURE() << "a 256² atlas of 32 × 32 frames was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("atlas_size"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace canopy
