#include "bench/shard_plan.h"

#include <algorithm>
#include <filesystem>
#include <numeric>
#include <system_error>

#include "common/error.h"
#include "common/lsystem.h"
#include "methods/method.h"

namespace canopy {
namespace {

// Leaves of the reference scale at which the CostHints were measured.
constexpr double kHintLeaves = 20000.0;
// An OBJ leaf quad takes about this many bytes (4 positions, normals, UVs and a face line).
constexpr double kFileBytesPerLeaf = 250.0;
// Reference seconds for one 512² view at 2×2 supersampling and for one forest tree-frame at 512²
// (the default run here, per 20,000-leaf tree); only the proportions between units matter.
constexpr double kViewSeconds = 0.04;
constexpr double kTreeFrameSeconds = 0.003;

// How large the tree is relative to the CostHints' 20,000 leaves, from the config alone.
double treeScale(const TreeSpec& spec) {
  double leaves = kHintLeaves;
  std::error_code error;
  if (spec.kind == TreeSpec::Kind::kPreset) {
    leaves = spec.leaves > 0 ? spec.leaves : treePreset(spec.preset).leaves;
  } else if (spec.kind == TreeSpec::Kind::kFile) {
    const auto bytes = std::filesystem::file_size(spec.file.path, error);
    if (!error) leaves = double(bytes) / kFileBytesPerLeaf;
  } else {
    // A capture folder: the volumetric bake reads every image; 100 images ≈ the hint's tree.
    size_t images = 0;
    for (auto it = std::filesystem::recursive_directory_iterator(spec.captures, error);
         !error && it != std::filesystem::recursive_directory_iterator(); it.increment(error)) {
      images += it->is_regular_file(error) ? 1 : 0;
    }
    leaves = kHintLeaves * double(images) / 100.0;
  }
  return std::max(leaves / kHintLeaves, 0.02);  // a tiny tree still costs its set-up
}

double unitCost(const ExperimentConfig& config, const TreeSpec& tree,
                const MethodVariant& variant) {
  const MethodTraits& traits = builtinMethods().find(variant.method).traits;
  const ViewSettings& views = config.views;
  const RenderSettings& render = views.render;
  const double viewPixels = double(render.width) * render.height * render.supersample *
                            render.supersample / (512.0 * 512.0 * 4.0);
  double viewCount = double(views.distances.size() * views.elevations.size()) * views.azimuths;
  if (views.closeups.enabled)
    viewCount += double(views.closeups.elevations.size()) * views.closeups.azimuths;
  // Each view is drawn by the method and scored against the reference's (cached per tree).
  double seconds = viewCount * kViewSeconds * viewPixels * (traits.cost.frameCost + 0.5);
  if (config.budget && traits.memoryKnob) seconds *= 1.0 + config.budget->maxSteps;
  for (int trees : config.forests.sizes) {
    const ForestTiming timing = config.forests.timingFor(trees);
    const double forestPixels = double(timing.width) * timing.height / (512.0 * 512.0);
    const double framesPerTree =
        double(timing.warmup + timing.blocks) + double(timing.frames) * std::max(timing.repeats, 1);
    seconds += framesPerTree * trees * kTreeFrameSeconds * std::max(forestPixels, 0.25) *
               (1.0 + traits.cost.frameCost);
  }
  if (config.popping.enabled) {
    const double poppingPixels =
        double(config.popping.width) * config.popping.height / (512.0 * 512.0);
    seconds += 4.0 * config.popping.frames * kViewSeconds * poppingPixels * traits.cost.frameCost;
  }
  return (traits.cost.bakeSeconds + seconds) * treeScale(tree);
}

}  // namespace

bool ShardPlan::runs(int shard, size_t tree, size_t variant) const {
  const auto& mine = units.at(size_t(shard));
  return std::any_of(mine.begin(), mine.end(), [&](const ShardUnit& unit) {
    return unit.tree == tree && unit.variant == variant;
  });
}

std::vector<ShardUnit> experimentUnits(const ExperimentConfig& config) {
  std::vector<ShardUnit> all;
  for (size_t t = 0; t < config.trees.size(); ++t) {
    for (size_t v = 0; v < config.variants.size(); ++v) {
      all.push_back({t, v, config.trees[t].label(), config.variants[v].label,
                     unitCost(config, config.trees[t], config.variants[v])});
    }
  }
  return all;
}

ShardPlan planShards(const ExperimentConfig& config, int shards, const std::string& option) {
  std::vector<ShardUnit> all = experimentUnits(config);
  if (shards < 1 || size_t(shards) > all.size()) {
    throwInputError("{}: {} shards asked for, but the config has {} (tree × method) unit(s)",
                    option, shards, all.size());
  }
  ShardPlan plan;
  plan.shards = shards;
  plan.units.resize(size_t(shards));
  plan.expectedCost.assign(size_t(shards), 0.0);
  std::vector<size_t> order(all.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return all[a].expectedCost > all[b].expectedCost; });
  for (size_t u : order) {
    const size_t lightest =
        size_t(std::min_element(plan.expectedCost.begin(), plan.expectedCost.end()) -
               plan.expectedCost.begin());
    plan.units[lightest].push_back(all[u]);
    plan.expectedCost[lightest] += all[u].expectedCost;
  }
  for (auto& mine : plan.units) {
    std::sort(mine.begin(), mine.end(), [](const ShardUnit& a, const ShardUnit& b) {
      return std::tie(a.tree, a.variant) < std::tie(b.tree, b.variant);
    });
  }
  return plan;
}

}  // namespace canopy
