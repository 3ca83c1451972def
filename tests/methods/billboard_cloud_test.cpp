#include "methods/common/billboard_cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>
#include <glm/geometric.hpp>

#include "bench/harness.h"
#include "common/error.h"
#include "common/metrics.h"
#include "common/random.h"
#include "common/views.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/mipmaps.h"
#include "methods/common/wood_capture.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

class Clustering : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    tree = new Tree(test::smallTree(1500, 9));
    ClusteringParams params;
    params.clusters = 60;
    cloud = new BillboardCloud(buildBillboardCloud(*tree, params, 4));
  }
  static void TearDownTestSuite() {
    delete cloud;
    delete tree;
  }
  static Tree* tree;
  static BillboardCloud* cloud;
};
Tree* Clustering::tree = nullptr;
BillboardCloud* Clustering::cloud = nullptr;

TEST_F(Clustering, EveryLeafIsInExactlyOneBillboard) {
  std::vector<int> seen(tree->leaves.size(), 0);
  ASSERT_GE(cloud->billboards.size(), 60u);  // 60 planes, some cut into pieces
  for (const Billboard& billboard : cloud->billboards) {
    EXPECT_FALSE(billboard.leaves.empty());
    for (uint32_t leaf : billboard.leaves) ++seen[leaf];
  }
  for (size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], 1) << "leaf " << i;
}

TEST_F(Clustering, SplitPiecesOfAPlaneLieMoreThanTheGapApartAndNoSplitKeepsKBillboards) {
  ClusteringParams params;
  params.clusters = 60;
  params.splitGap = 0.0f;
  EXPECT_EQ(buildBillboardCloud(*tree, params, 4).billboards.size(), 60u);
  // Independently: the pieces of one plane (same normal and offset) have projected leaf boxes
  // that, grown by half the gap each, do not overlap.
  const float gap = ClusteringParams{}.splitGap * cloud->meanLeafLength;
  size_t planesSplit = 0;
  for (size_t a = 0; a < cloud->billboards.size(); ++a) {
    for (size_t b = a + 1; b < cloud->billboards.size(); ++b) {
      const Billboard &p = cloud->billboards[a], &q = cloud->billboards[b];
      if (p.normal != q.normal ||
          std::abs(glm::dot(p.center - q.center, p.normal)) > 1e-4f * tree->boundingSphereRadius())
        continue;
      ++planesSplit;
      // The split measures boxes along the plane axes the clustering picks for a normal.
      const glm::vec3 helper =
          std::abs(p.normal.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
      const glm::vec3 e1 = glm::normalize(glm::cross(helper, p.normal));
      const glm::vec3 e2 = glm::cross(p.normal, e1);
      const auto project = [&](const glm::vec3& x) {
        return glm::vec2(glm::dot(x, e1), glm::dot(x, e2));
      };
      // Boxes may overlap through a chain of leaves' boxes only if the pieces were one group;
      // pieces of one plane are different groups, so no single pair of leaf boxes overlaps.
      for (uint32_t i : p.leaves) {
        for (uint32_t j : q.leaves) {
          glm::vec2 iLo(1e9f), iHi(-1e9f), jLo(1e9f), jHi(-1e9f);
          for (int c = 0; c < 4; ++c) {
            const glm::vec2 u = project(tree->leaves[i].corner(c));
            const glm::vec2 v = project(tree->leaves[j].corner(c));
            iLo = glm::min(iLo, u), iHi = glm::max(iHi, u), jLo = glm::min(jLo, v),
            jHi = glm::max(jHi, v);
          }
          const bool overlap = iLo.x - gap < jHi.x && jLo.x - gap < iHi.x && iLo.y - gap < jHi.y &&
                               jLo.y - gap < iHi.y;
          EXPECT_FALSE(overlap) << "leaves " << i << " and " << j;
        }
      }
    }
  }
  EXPECT_GT(planesSplit, 0u) << "the default gap splits some planes of this tree";
}

TEST_F(Clustering, LeafVerticesAreWithinTheReportedPlaneDistance) {
  for (const Billboard& billboard : cloud->billboards) {
    EXPECT_NEAR(glm::length(billboard.normal), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(billboard.normal, billboard.axisU), 0.0f, 1e-5f);
    for (uint32_t leaf : billboard.leaves) {
      for (int c = 0; c < 4; ++c) {
        const float distance =
            std::abs(glm::dot(tree->leaves[leaf].corner(c) - billboard.center, billboard.normal));
        EXPECT_LE(distance, billboard.maxPlaneDistance * (1 + 1e-4f) + 1e-6f);
        EXPECT_LE(distance, cloud->maxPlaneDistance * (1 + 1e-4f) + 1e-6f);
      }
    }
  }
  EXPECT_LE(cloud->meanPlaneDistance, cloud->maxPlaneDistance);
  EXPECT_GT(cloud->quadArea, 0.0);
}

TEST_F(Clustering, QuadsContainTheirLeavesProjections) {
  for (const Billboard& billboard : cloud->billboards) {
    const float slack = 1e-4f * tree->boundingSphereRadius();
    for (uint32_t leaf : billboard.leaves) {
      for (int c = 0; c < 4; ++c) {
        const glm::vec2 p = billboard.toPlane(tree->leaves[leaf].corner(c));
        EXPECT_LE(std::abs(p.x), billboard.halfExtents.x + slack);
        EXPECT_LE(std::abs(p.y), billboard.halfExtents.y + slack);
      }
    }
  }
}

TEST_F(Clustering, IsDeterministicAndUsesOrientation) {
  ClusteringParams params;
  params.clusters = 60;
  const BillboardCloud again = buildBillboardCloud(*tree, params, 4);
  for (size_t b = 0; b < again.billboards.size(); ++b)
    EXPECT_EQ(again.billboards[b].leaves, cloud->billboards[b].leaves);
  // Leaves agree with their billboard's orientation better than with a random plane.
  double alignment = 0.0;
  for (const Billboard& billboard : cloud->billboards) {
    for (uint32_t leaf : billboard.leaves)
      alignment += std::abs(glm::dot(billboard.normal, tree->leaves[leaf].normal));
  }
  EXPECT_GT(alignment / double(tree->leaves.size()), 0.6);  // a uniformly random plane gives 0.5
}

TEST(ClusteringBadInput, ClusterCountOutOfRangeNamesTheParameter) {
  const Tree tree = test::smallTree(50);
  for (int k : {0, -3}) {
    ClusteringParams params;
    params.clusters = k;
    try {
      buildBillboardCloud(tree, params, 1);
      FAIL() << k;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("clusters"), std::string::npos) << error.what();
    }
  }
  const auto& create = builtinMethods().find("billboard_cloud").create;
  EXPECT_THROW(create({{"clusters", 0}}, "test"), InputError);
  EXPECT_THROW(create({{"density", 0.0}}, "test"), InputError);
  EXPECT_THROW(create({{"density", -5.0}}, "test"), InputError);
  EXPECT_THROW(create({{"lod_near_px", 30.0}, {"lod_far_px", 60.0}}, "test"), InputError);
  EXPECT_THROW(create({{"clusters", 100}, {"clusters_mid", 200}}, "test"), InputError);
  EXPECT_THROW(create({{"clusters_mid", 20}, {"clusters_far", 30}}, "test"), InputError);
  // Unset coarse counts are written back as the counts used: K/3 and K/10.
  const auto method = create({{"clusters", 100}}, "test");
  EXPECT_EQ(method->effectiveParams().at("clusters_mid"), 33);
  EXPECT_EQ(method->effectiveParams().at("clusters_far"), 10);
}

// `density` is per unit of the tree's own length: the bake reports what it gives per bounding
// radius, and warns, naming the key, when that is far above what the defaults were measured at
// (a tree modelled in other units than metres).
TEST(BillboardCloudDensity, TexelsPerRadiusAreReportedAndATreeInOtherUnitsIsWarnedAbout) {
  const Tree tree = test::smallTree(50);
  const float radius = tree.boundingSphereRadius();
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(16);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("density_test", sink));
  const auto bake = [&](float density) {
    auto method =
        builtinMethods()
            .find("billboard_cloud")
            .create({{"density", density}, {"clusters", 8}, {"lod", false}, {"supersample", 1}},
                    "test");
    BakeContext context;
    method->bake(tree, context);
    return method->bakeReport().at("texels_per_bounding_radius").get<float>();
  };
  // Texels per radius the method measures against: about broadleaf's at the default density.
  const float measured = 120.0f;
  EXPECT_NEAR(bake(16.0f), 16.0f * radius, 1e-3f * radius);
  EXPECT_TRUE(sink->last_formatted().empty()) << "a tree in metres is not warned about";
  const float tooDense = 5.0f * measured / radius;  // as if the tree were in units 5x smaller
  EXPECT_NEAR(bake(tooDense), 5.0f * measured, 1e-2f * measured);
  spdlog::set_default_logger(previous);
  const auto logged = sink->last_formatted();
  ASSERT_EQ(logged.size(), 1u);
  EXPECT_NE(logged[0].find("'density'"), std::string::npos) << logged[0];
  EXPECT_NE(logged[0].find("warning"), std::string::npos) << logged[0];
}

TEST(ClusteringSmallTree, MoreClustersThanLeavesGivesOnePlanePerLeaf) {
  const Tree tree = test::smallTree(50);
  ClusteringParams params;
  params.clusters = 400;  // a default sized for full trees
  const BillboardCloud cloud = buildBillboardCloud(tree, params, 1);
  EXPECT_EQ(cloud.clusters, 50);
  size_t listed = 0;
  for (const Billboard& billboard : cloud.billboards) {
    EXPECT_EQ(billboard.leaves.size(), 1u);
    listed += billboard.leaves.size();
  }
  EXPECT_EQ(listed, tree.leaves.size());
}

TEST(MinimumAreaRectangle, FindsTheRotatedRectangle) {
  // Corners of a 4 × 1 rectangle rotated by 30°, plus interior points.
  const float angle = 0.5235988f;
  const glm::vec2 u(std::cos(angle), std::sin(angle)), v(-std::sin(angle), std::cos(angle));
  std::vector<glm::vec2> points;
  for (float a : {-2.0f, 2.0f})
    for (float b : {-0.5f, 0.5f}) points.push_back(glm::vec2(3, 1) + u * a + v * b);
  points.push_back(glm::vec2(3, 1));
  points.push_back(glm::vec2(3, 1) + u * 1.0f);
  const Rectangle2D rectangle = minimumAreaRectangle(points);
  EXPECT_NEAR(rectangle.halfExtents.x * rectangle.halfExtents.y * 4, 4.0f, 1e-4f);
  EXPECT_NEAR(rectangle.center.x, 3.0f, 1e-4f);
  EXPECT_NEAR(rectangle.center.y, 1.0f, 1e-4f);
  EXPECT_NEAR(std::abs(glm::dot(rectangle.axis, u)) + std::abs(glm::dot(rectangle.axis, v)), 1.0f,
              1e-4f);
}

TEST(CoveragePreservingMips, KeepTheCoveredAreaAfterFilteringAtEveryLevel) {
  // Small round "leaves" (alpha = the covered share of each texel, as the captures write it):
  // box filtering alone lets their averaged alpha fall under 0.5, and counting passing texels
  // ignores what bilinear filtering cuts off between them.
  ImageRgba8 image(64, 64);
  Random random(5, 1);
  std::vector<glm::vec3> discs;  // centre x, y and radius, in texels
  for (int i = 0; i < 40; ++i)
    discs.emplace_back(random.uniform() * 64, random.uniform() * 64,
                       1.0f + 2.0f * random.uniform());
  double covered = 0.0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      int inside = 0;
      for (int s = 0; s < 64; ++s) {
        const glm::vec2 p(x + (s % 8 + 0.5f) / 8, y + (s / 8 + 0.5f) / 8);
        for (const glm::vec3& d : discs) {
          if (glm::length(p - glm::vec2(d)) < d.z) {
            ++inside;
            break;
          }
        }
      }
      uint8_t* texel = image.at(x, y);
      texel[1] = 200;
      texel[3] = static_cast<uint8_t>(std::lround(255.0 * inside / 64.0));
      covered += texel[3] / 255.0;
    }
  }
  covered /= 64.0 * 64.0;
  // Plain box filtering to 8×8 (level 3), for comparison.
  ImageRgba8 box(8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      int sum = 0;
      for (int k = 0; k < 64; ++k) sum += image.at(x * 8 + k % 8, y * 8 + k / 8)[3];
      box.at(x, y)[3] = static_cast<uint8_t>(sum / 64);
    }
  for (const Compression compression : {Compression::kNone, Compression::kDxt1}) {
    const bool binary = compression == Compression::kDxt1;
    const auto levels = buildCoveragePreservingMips(image, compression);
    ASSERT_EQ(levels.size(), 7u);
    EXPECT_GT(std::abs(alphaTestedArea(box, binary) - covered), 0.05) << "box filtering loses it";
    for (size_t l = 0; l <= 3; ++l)
      EXPECT_NEAR(alphaTestedArea(levels[l], binary), covered, 0.03) << "level " << l;
    // Colour stays the covered texels' colour (alpha-weighted), not darkened by empty texels.
    for (size_t l = 1; l <= 3; ++l) {
      const ImageRgba8& level = levels[l];
      for (size_t i = 0; i < level.pixels.size(); i += 4) {
        if (level.pixels[i + 3] > 0) {
          EXPECT_NEAR(level.pixels[i + 1], 200, 2);
        }
      }
    }
  }
  // Whole-tree frames keep level 0 as captured and match its tested area further down.
  const auto kept =
      buildCoveragePreservingMips(image, Compression::kNone, true, CoverageTarget::kLevelZeroTest);
  EXPECT_EQ(kept[0].pixels, image.pixels);
  const double levelZeroArea = alphaTestedArea(image, false);
  for (size_t l = 1; l <= 3; ++l)
    EXPECT_NEAR(alphaTestedArea(kept[l], false), levelZeroArea, 0.03) << "level " << l;
}

// A billboard seen along its normal shows what the polygonal leaves of its cluster show.
TEST(BillboardCapture, BillboardSeenAlongItsNormalMatchesItsLeaves) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  Tree full = test::smallTree(1500, 9);
  ClusteringParams params;
  params.clusters = 60;
  const BillboardCloud cloud = buildBillboardCloud(full, params, 4);
  // The flattest well-populated cluster, as a tree of its own (leaves only).
  const Billboard* chosen = nullptr;
  for (const Billboard& b : cloud.billboards) {
    if (b.leaves.size() >= 15 && (!chosen || b.meanPlaneDistance < chosen->meanPlaneDistance))
      chosen = &b;
  }
  ASSERT_NE(chosen, nullptr);
  Tree cluster;
  cluster.leafTextures = full.leafTextures;
  for (uint32_t i : chosen->leaves) {
    Leaf leaf = full.leaves[i];
    leaf.branch = -1;
    cluster.leaves.push_back(leaf);
  }
  finalizeTree(cluster, "cluster");
  RenderSettings settings;
  settings.width = settings.height = 128;
  settings.fovYDegrees = 2.0f;  // far and narrow: nearly orthographic, as the capture
  Harness harness(device, settings);
  const auto render = [&](const std::string& method, const nlohmann::json& p) {
    auto m = test::bakeAndUpload(device, cluster, method, p);
    const float radius = cluster.boundingSphereRadius();
    Camera camera;
    camera.target = chosen->center;
    camera.position = chosen->center + chosen->normal * (radius * 60.0f);
    camera.up = chosen->axisV;
    camera.fovYDegrees = settings.fovYDegrees;
    camera.nearPlane = radius * 55.0f;
    camera.farPlane = radius * 65.0f;
    return harness.render(*m, camera);
  };
  // Density: about two texels per screen pixel of the 128² view, so the capture is not the limit.
  const float pixelsPerUnit = 128.0f / (2.0f * 60.0f * cluster.boundingSphereRadius() *
                                        std::tan(0.5f * 2.0f * 3.14159265f / 180.0f));
  const ImageRgba8 reference = render("polygonal", {{"wood", false}});
  const ImageRgba8 billboard = render("billboard_cloud", {{"clusters", 1},
                                                          {"lod", false},
                                                          {"wood", false},
                                                          {"density", 2.0f * pixelsPerUnit},
                                                          {"max_billboard_texels", 4096}});
  const ImageMetrics metrics = compareImages(reference, billboard);
  std::printf("billboard vs its leaves: PSNR %.2f dB, SSIM %.3f, coverage error %.4f\n",
              metrics.psnr, metrics.ssim, metrics.coverageError);
  // Floor: the two images differ by resampling (leaf texture → billboard texels → screen) and by
  // the parallax of leaves off the plane. Measured here: 25.8 dB, SSIM 0.989; the 20 dB floor
  // leaves room for other drivers' filtering while any misplaced leaf pattern falls far below.
  EXPECT_GT(metrics.psnr, 20.0) << "ssim " << metrics.ssim << " coverage error "
                                << metrics.coverageError;
  EXPECT_LT(metrics.coverageError, 0.15);
}

// Wood in billboard images (wood_capture_px): a triangle goes to the nearest plane whose
// rectangle holds it within the distance bound, and the capture draws it opaque in its albedo
// over exactly its projected area.
TEST(WoodCapture, NearestPlaneWithinTheBoundHoldsTheTriangleAndTheImageShowsIt) {
  Tree tree;
  tree.woodMaterials = {{"bark", glm::vec4(0.5f, 0.25f, 0.125f, 1.0f), -1}};
  const auto addTriangle = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    for (const glm::vec3& p : {a, b, c}) {
      tree.wood.indices.push_back(uint32_t(tree.wood.positions.size()));
      tree.wood.positions.push_back(p);
      tree.wood.normals.emplace_back(0.0f, 0.0f, 1.0f);
      tree.wood.uvs.emplace_back(0.0f);
    }
    tree.wood.materialIds.push_back(0);
  };
  addTriangle({-0.5f, -0.5f, 0.01f}, {0.5f, -0.5f, 0.01f}, {-0.5f, 0.5f, 0.02f});  // in plane 0
  addTriangle({-0.5f, -0.5f, 0.5f}, {0.5f, -0.5f, 0.5f}, {-0.5f, 0.5f, 0.5f});     // too far
  addTriangle({0.5f, 0.5f, 0.0f}, {1.5f, 0.5f, 0.0f}, {0.5f, 0.9f, 0.0f});         // sticks out
  addTriangle({-0.5f, -0.5f, 0.05f}, {0.5f, -0.5f, 0.05f}, {-0.5f, 0.5f, 0.04f});  // plane 1
  std::vector<Billboard> planes(2);
  for (int i = 0; i < 2; ++i) {
    planes[size_t(i)].center = {0.0f, 0.0f, 0.06f * float(i)};
    planes[size_t(i)].halfExtents = {1.0f, 1.0f};
  }
  const auto assigned = assignWoodToBillboards(tree.wood, planes, 0.1f);
  EXPECT_EQ(assigned[0], std::vector<uint32_t>{0});
  EXPECT_EQ(assigned[1], std::vector<uint32_t>{3});
  EXPECT_TRUE(assignWoodToBillboards(tree.wood, planes, 0.005f)[0].empty())
      << "0.01–0.02 off the plane is beyond a 0.005 bound";

  const LeafImageSampler leaves(tree);
  const WoodColorSampler colors(tree);
  for (const bool back : {false, true}) {
    const ImageRgba8 image = captureLeavesOrthographic(tree, leaves, {}, planes[0], 64, 64, 4, back,
                                                       &colors, assigned[0]);
    double covered = 0.0;
    for (int y = 0; y < 64; ++y) {
      for (int x = 0; x < 64; ++x) {
        covered += image.at(x, y)[3] / 255.0;
        // Texel centres well inside the triangle (u, v in texels from (−1, −1)).
        const float u = (x + 0.5f) / 32.0f - 1.0f, v = (y + 0.5f) / 32.0f - 1.0f;
        if (u > -0.45f && v > -0.45f && u + v < -0.05f) {
          ASSERT_EQ(image.at(x, y)[3], 255) << x << "," << y;
          EXPECT_NEAR(image.at(x, y)[0], 0.5 * 255, 1.5);  // the base colour, sRGB as stored
          EXPECT_NEAR(image.at(x, y)[1], 0.25 * 255, 1.5);
        }
      }
    }
    // The triangle's area, 0.5, over the 2 × 2 plane is 1/8 of the 4096 texels.
    EXPECT_NEAR(covered / (64.0 * 64.0), 0.125, 0.005) << (back ? "back" : "front");
  }
}

// wood_capture_parts: triangles that share a corner position are one part (files split vertices
// along seams, so indices do not say it), and a part goes whole to the nearest plane that holds
// every corner of it within the bound, or stays geometry whole.
TEST(WoodCapture, PartsGoWholeToTheNearestPlaneThatHoldsThemOrStayGeometry) {
  WoodMesh wood;
  const auto addTriangle = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    for (const glm::vec3& p : {a, b, c}) {
      wood.indices.push_back(uint32_t(wood.positions.size()));
      wood.positions.push_back(p);
      wood.normals.emplace_back(0.0f, 0.0f, 1.0f);
      wood.uvs.emplace_back(0.0f);
    }
    wood.materialIds.push_back(0);
  };
  // Part 0, two triangles sharing an edge: 0.08 from plane 0 at most, 0.05 from plane 1.
  addTriangle({-0.5f, -0.5f, 0.01f}, {0.5f, -0.5f, 0.01f}, {-0.5f, 0.5f, 0.02f});
  addTriangle({0.5f, -0.5f, 0.01f}, {-0.5f, 0.5f, 0.02f}, {0.5f, 0.5f, 0.08f});
  // Part 1, sharing a corner: its first triangle sticks out of both rectangles.
  addTriangle({0.6f, 0.6f, 0.0f}, {1.5f, 0.6f, 0.0f}, {0.6f, 0.9f, 0.0f});
  addTriangle({0.6f, 0.6f, 0.0f}, {0.9f, 0.6f, 0.0f}, {0.6f, 0.8f, 0.0f});
  std::vector<Billboard> planes(2);
  for (int i = 0; i < 2; ++i) {
    planes[size_t(i)].center = {0.0f, 0.0f, 0.06f * float(i)};
    planes[size_t(i)].halfExtents = {1.0f, 1.0f};
  }
  const std::vector<uint32_t> parts = woodParts(wood);
  EXPECT_EQ(parts, (std::vector<uint32_t>{0, 0, 1, 1}));
  const auto whole = assignWoodPartsToBillboards(wood, parts, planes, 0.1f);
  EXPECT_TRUE(whole[0].empty()) << testing::PrintToString(whole[0]);
  EXPECT_EQ(whole[1], (std::vector<uint32_t>{0, 1}))
      << "part 0 whole in the plane nearest all of it";
  // A triangle at a time, part 0 splits between the planes and part 1's inner triangle is taken.
  const auto single = assignWoodToBillboards(wood, planes, 0.1f);
  EXPECT_EQ(single[0], (std::vector<uint32_t>{0, 3}));
  EXPECT_EQ(single[1], (std::vector<uint32_t>{1}));
  // Below the part's distance to its nearest plane nothing holds it.
  const auto tight = assignWoodPartsToBillboards(wood, parts, planes, 0.04f);
  EXPECT_TRUE(tight[0].empty() && tight[1].empty());
  // The method writes the option back as it takes effect: off where no wood is captured.
  const auto& create = builtinMethods().find("billboard_cloud").create;
  EXPECT_TRUE(create({{"wood_capture_parts", true}}, "test")
                  ->effectiveParams()
                  .at("wood_capture_parts")
                  .get<bool>());
  EXPECT_FALSE(create({{"wood_capture_parts", true}, {"lod", false}}, "test")
                   ->effectiveParams()
                   .at("wood_capture_parts")
                   .get<bool>());
}

// alpha_test "hashed": where the atlas is minified its mip levels average several texels, and a
// threshold hashed per pixel and primitive keeps that averaged coverage in expectation instead of
// making it all or nothing at 0.5; where it is magnified the test stays at 0.5.
TEST(BillboardCloudAlphaTest, HashedFollowsTheCrownWhereMinifiedAndKeepsOutlinesWhereMagnified) {
  const Tree tree = test::smallTree(1000, 3);  // the sparse preset's own leaf count
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  RenderSettings settings;
  settings.width = settings.height = 128;
  Harness harness(device, settings);
  const nlohmann::json fixedParams = {{"lod", false}, {"wood", false}, {"alpha_test", "fixed"}};
  nlohmann::json hashedParams = fixedParams;
  hashedParams["alpha_test"] = "hashed";
  auto reference = test::bakeAndUpload(device, tree, "polygonal", {{"wood", false}},
                                       Shading::kUnlit, "reference");
  auto fixed =
      test::bakeAndUpload(device, tree, "billboard_cloud", fixedParams, Shading::kUnlit, "fixed");
  auto hashed =
      test::bakeAndUpload(device, tree, "billboard_cloud", hashedParams, Shading::kUnlit, "hashed");
  EXPECT_EQ(hashed->effectiveParams().at("alpha_test"), "hashed");
  // Far: 12 radii, about 15 px of radius, every texel minified.
  const Camera far = orbitCamera(tree.bounds, {12.0f, 20.0f, 40.0f}, 40.0f);
  const ImageRgba8 referenceFar = harness.render(*reference, far);
  const double fixedError = compareImages(referenceFar, harness.render(*fixed, far)).coverageError;
  const double hashedError =
      compareImages(referenceFar, harness.render(*hashed, far)).coverageError;
  std::printf("coverage error at 12 radii: fixed %.4f, hashed %.4f\n", fixedError, hashedError);
  // Measured: 0.319 fixed (the crown's partly covered minified texels all or nothing), 0.258
  // hashed; a tenth lower is the floor.
  EXPECT_LT(hashedError, 0.9 * fixedError);
  // Near: a 10° close-up, leaves tens of pixels wide, the atlas magnified except where a billboard
  // is seen nearly edge-on. Measured: 2 % of the covered pixels differ from the fixed test's;
  // hashing every texel (the minification gate removed) made 73 % differ.
  const Camera near = orbitCamera(tree.bounds, {1.5f, 20.0f, 40.0f}, 10.0f);
  const ImageRgba8 fixedNear = harness.render(*fixed, near);
  const ImageRgba8 hashedNear = harness.render(*hashed, near);
  size_t covered = 0, differing = 0;
  for (size_t i = 3; i < fixedNear.pixels.size(); i += 4) {
    covered += fixedNear.pixels[i] > 0 || hashedNear.pixels[i] > 0;
    differing += fixedNear.pixels[i] != hashedNear.pixels[i];
  }
  std::printf("close-up: %zu of %zu covered pixels differ\n", differing, covered);
  ASSERT_GT(covered, 1000u);
  EXPECT_LT(double(differing), 0.1 * double(covered));
}

}  // namespace
}  // namespace canopy
