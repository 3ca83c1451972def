#include "bench/render_from_assets.h"

#include <fmt/format.h>

#include "bench/experiment.h"
#include "bench/harness.h"
#include "bench/run_meta.h"
#include "bench/run_names.h"
#include "bench/tree_session.h"
#include "common/tree_source.h"
#include "methods/method.h"

namespace canopy {

namespace {

// The item of `items` whose label is `wanted`; InputError listing the labels there are.
template <typename Item, typename Label>
const Item& findLabelled(const std::vector<Item>& items, const std::string& wanted,
                         const std::string& option, Label label) {
  std::vector<std::string> known;
  for (const Item& item : items) {
    if (label(item) == wanted) return item;
    if (known.size() < 12) known.push_back(label(item));
  }
  throwInputError("{}: '{}' is not in the config (it has {}{})", option, wanted,
                  fmt::join(known, ", "), known.size() < items.size() ? ", …" : "");
}

// Loads a saved asset; any failure is an InputError naming the folder (a bad asset is the user's
// file, not Canopy's bug).
void loadAsset(Method& method, const std::filesystem::path& folder, const std::string& methodName) {
  if (!std::filesystem::is_regular_file(folder / "asset.json"))
    throwInputError("{}: no saved asset (asset.json missing)", folder.string());
  AssetFolder asset(folder);
  try {
    method.load(asset);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& error) {
    throwInputError("{}: not a loadable {} asset ({})", folder.string(), methodName, error.what());
  }
}

}  // namespace

void renderFromAssets(const RenderFromAssetsRequest& request) {
  const ExperimentConfig config = readExperimentConfig(request.config);
  const std::filesystem::path run =
      request.run.empty() ? std::filesystem::path("results") / config.name : request.run;
  const RunMeta meta = readRunMeta(run);
  if (meta.configHash && *meta.configHash != config.hash) {
    throwInputError("{}: holds a run of config {}, not of {} ({}); its assets would not match",
                    run.string(), *meta.configHash, request.config, config.hash);
  }
  const TreeSpec& spec = findLabelled(config.trees, request.tree, "--tree",
                                      [](const TreeSpec& tree) { return tree.label(); });
  const MethodVariant& variant = findLabelled(config.variants, request.variant, "--variant",
                                              [](const MethodVariant& v) { return v.label; });
  const std::filesystem::path folder =
      run / "assets" / safeName(spec.label()) / safeName(variant.label);
  const Tree tree = loadTree(spec);
  const std::vector<EvalView> views = evaluationViews(tree, config.views);
  const EvalView& view =
      findLabelled(views, request.view, "--view", [](const EvalView& v) { return v.key; });

  auto context = gl::createContext({request.backend});
  gl::Ledger ledger;
  gl::Device device(ledger);
  Harness harness(device, config.views.render);
  harness.setTree(tree.bounds, tree.leaves.size());
  auto method =
      builtinMethods().find(variant.method).create(variant.params, "methods." + variant.label);
  loadAsset(*method, folder, variant.method);
  {
    gl::Device::OwnerScope owner(device, variant.label);
    method->upload(device);
  }
  gl::checkError(("upload of " + variant.label).c_str());
  const ImageRgba8 image =
      harness.display(harness.renderLinearAt(*method, view.camera, view.width, view.height));
  writePng(request.image, withOpaqueAlpha(image));
}

}  // namespace canopy
