#include "bench/capture_export.h"

#include "bench/harness.h"
#include "common/captures.h"
#include "methods/method.h"

namespace canopy {

void exportCaptures(const Tree& tree, const std::filesystem::path& folder,
                    const CaptureExportOptions& options, gl::Backend backend) {
  auto context = gl::createContext({backend});
  gl::Ledger ledger;
  gl::Device device(ledger);
  RenderSettings settings;
  settings.supersample = options.supersample;
  Harness harness(device, settings);
  auto reference = builtinMethods().find("polygonal").create(nlohmann::json::object(), "export");
  BakeContext bake;
  reference->bake(tree, bake);
  {
    gl::Device::OwnerScope owner(device, "polygonal");
    reference->upload(device);
  }
  const auto photograph = [&](const std::vector<Camera>& cameras) {
    std::vector<CapturedView> views;
    views.reserve(cameras.size());
    for (const Camera& camera : cameras) {
      views.push_back(
          {camera,
           harness.renderLinearAt(*reference, camera, options.resolution, options.resolution), ""});
    }
    return views;
  };
  // Test views sit half-way between the train azimuths of the same rings.
  const auto train =
      photograph(captureRingCameras(tree.bounds, options.trainViews, options.distance, 5.0f));
  const auto test = photograph(captureRingCameras(tree.bounds, options.testViews, options.distance,
                                                  5.0f + 180.0f / float(options.testViews)));
  std::filesystem::create_directories(folder);
  writeNerfCaptures(folder, train, test);
}

}  // namespace canopy
