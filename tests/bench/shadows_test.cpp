// Lit frames with shadows: the shadow map is rendered with the method itself, so shadows can
// only take light away — every pixel a method covers is as dark or darker with shadows, and the
// reference really does shadow some of its leaves.
#include <gtest/gtest.h>

#include "bench/harness.h"
#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

double meanLuma(const ImageRgba8& image) {
  double sum = 0.0;
  long n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (image.at(x, y)[3] == 255) sum += image.at(x, y)[1], ++n;
  return n ? sum / double(n) : 0.0;
}

class Shadows : public testing::TestWithParam<std::string> {};

TEST_P(Shadows, OnlyTakeLightAwayAndDarkenTheTree) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = test::smallTree(600, 5);
  RenderSettings settings;
  settings.width = settings.height = 128;
  settings.shading = Shading::kLit;
  settings.lightDirection = {0.2f, 1.0f, 0.3f};
  Harness harness(device, settings);
  harness.setTree(tree.bounds, tree.leaves.size());
  auto method = builtinMethods().find(GetParam()).create(nlohmann::json::object(), "test");
  BakeContext bake;
  method->bake(tree, bake);
  {
    gl::Device::OwnerScope owner(device, "m");
    method->upload(device);
  }
  const Camera camera = orbitCamera(tree.bounds, {2.5f, 20.0f, 30.0f}, 40.0f);
  const ImageRgba8 lit = harness.render(*method, camera);
  harness.settings().shadows = true;
  const ImageRgba8 shadowed = harness.render(*method, camera);
  EXPECT_EQ(harness.render(*method, camera), shadowed) << "deterministic";
  long brighter = 0, covered = 0;
  for (int y = 0; y < lit.height; ++y) {
    for (int x = 0; x < lit.width; ++x) {
      const uint8_t *a = lit.at(x, y), *b = shadowed.at(x, y);
      if (a[3] != 255 || b[3] != 255) continue;
      ++covered;
      brighter += b[1] > a[1] + 1 ? 1 : 0;
    }
  }
  ASSERT_GT(covered, 300);
  EXPECT_EQ(brighter, 0) << "a shadow never adds light";
  EXPECT_LT(meanLuma(shadowed), meanLuma(lit) - 2.0) << "leaves shade one another";
  EXPECT_EQ(gl::api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// Every method that shades with the harness's light (volumetric_opacity shows photographs).
INSTANTIATE_TEST_SUITE_P(LitMethods, Shadows,
                         testing::Values("polygonal", "billboard_cloud", "single_leaf_indirect",
                                         "multilayer_indirect", "bbox_hierarchy"),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace canopy

namespace canopy {
namespace {

// Lit fairness: in lit runs the reference's leaves get the Embree AO the impostors bake, so AO
// is not error; views.ambient_occlusion false turns it off for the reference and impostors.
TEST(LitFairness, TheReferenceGetsTheImpostorsAmbientOcclusionOrNobodyDoes) {
  auto context = test::makeTestContext();
  gl::Ledger ledger;
  gl::Device device(ledger);
  const Tree tree = test::smallTree(600, 5);
  RenderSettings settings;
  settings.width = settings.height = 96;
  settings.shading = Shading::kLit;
  Harness harness(device, settings);
  harness.setTree(tree.bounds, tree.leaves.size());
  const auto bake = [&](const std::string& name, const nlohmann::json& params, Shading shading,
                        const std::string& owner) {
    return test::bakeAndUpload(device, tree, name, params, shading, owner);
  };
  const Camera camera = orbitCamera(tree.bounds, {2.5f, 20.0f, 30.0f}, 40.0f);
  // Baked for a lit run, the reference carries AO (its ledger shows the per-vertex values) and
  // its ambient term is darker than the same reference baked for an unlit run.
  auto withAo = bake("polygonal", nlohmann::json::object(), Shading::kLit, "ao");
  auto withoutAo = bake("polygonal", nlohmann::json::object(), Shading::kUnlit, "plain");
  EXPECT_GT(ledger.totals("ao").geometry, ledger.totals("plain").geometry);
  const ImageRgba8 occluded = harness.render(*withAo, camera);
  const ImageRgba8 open = harness.render(*withoutAo, camera);
  EXPECT_LT(meanLuma(occluded), meanLuma(open) - 1.0);
  // Off for everyone: the flag makes AO-baked and AO-free bakes render the same image, for the
  // reference and for an impostor that bakes AO.
  harness.settings().ambientOcclusion = false;
  EXPECT_EQ(harness.render(*withAo, camera), harness.render(*withoutAo, camera));
  const nlohmann::json cloud = {{"clusters", 30}, {"hash_resolution", 8}};
  nlohmann::json noAo = cloud;
  noAo["ambient_occlusion"] = false;
  auto layered = bake("multilayer_indirect", cloud, Shading::kLit, "ml");
  auto layeredPlain = bake("multilayer_indirect", noAo, Shading::kLit, "ml_plain");
  EXPECT_EQ(harness.render(*layered, camera), harness.render(*layeredPlain, camera));
  harness.settings().ambientOcclusion = true;
  EXPECT_NE(harness.render(*layered, camera), harness.render(*layeredPlain, camera));
}

}  // namespace
}  // namespace canopy
