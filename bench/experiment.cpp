#include "bench/experiment.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "common/camera_path.h"
#include "common/config.h"
#include "methods/method.h"

namespace canopy {

std::vector<nlohmann::json> expandSweep(const nlohmann::json& params) {
  std::vector<nlohmann::json> points{nlohmann::json::object()};
  for (const auto& [key, value] : params.items()) {
    std::vector<nlohmann::json> next;
    const bool sweep = value.is_array();
    if (sweep && value.empty())
      throwInputError("config params.{}: an empty list sweeps nothing", key);
    for (const nlohmann::json& point : points) {
      if (sweep) {
        for (const nlohmann::json& option : value) {
          nlohmann::json extended = point;
          extended[key] = option;
          next.push_back(std::move(extended));
        }
      } else {
        nlohmann::json extended = point;
        extended[key] = value;
        next.push_back(std::move(extended));
      }
    }
    points = std::move(next);
  }
  return points;
}

std::string hashJson(const nlohmann::json& json) {
  const std::string text = json.dump();
  uint64_t hash = 14695981039346656037ULL;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ULL;
  }
  return fmt::format("fnv1a64:{:016x}", hash);
}

ForestTiming ForestSettings::timingFor(int trees) const {
  if (largeFrom <= 0 || trees < largeFrom) return timing;
  ForestTiming large = timing;
  large.frames = largeFrames;
  large.warmup = largeWarmup;
  large.blocks = 1;
  return large;
}

namespace {

std::string variantLabel(const std::string& method, const nlohmann::json& params) {
  if (params.empty()) return method;
  std::string label = method + "[";
  bool first = true;
  for (const auto& [key, value] : params.items()) {
    label += (first ? "" : ",") + key + "=" +
             (value.is_string() ? value.get<std::string>() : value.dump());
    first = false;
  }
  return label + "]";
}

// Reads a config section through its struct's visit(): typed, range-checked, unknown keys named.
template <typename Section>
void readSection(ConfigObject& config, Section& section, const std::string& name) {
  ParamReader reader(config, "config");
  section.visit(reader);
  config.finish(name);
}

ViewSettings parseViews(ConfigObject& config) {
  ViewSettings views;
  readSection(config, views, "views");
  const RenderSettings& render = views.render;
  if (glm::length(render.lightDirection) < 1e-3f) {
    throwInputError("config {}: the light direction must not be zero",
                    config.keyPath("light_direction"));
  }
  if (render.shadows && render.shading != Shading::kLit)
    throwInputError(R"(config {}: shadows need "shading": "lit")", config.keyPath("shadows"));
  return views;
}

CloseupSettings parseCloseups(ConfigObject& config) {
  CloseupSettings closeups;
  closeups.enabled = true;
  readSection(config, closeups, "views.closeups");
  return closeups;
}

ForestSettings parseForests(ConfigObject& config, const RenderSettings& render,
                            const std::string& baseDirectory) {
  ForestSettings forests;
  forests.timing.width = render.width;
  forests.timing.height = render.height;
  // Without "blocks", as many as the frames allow up to the default.
  const ForestTiming defaults;
  if (const nlohmann::json* frames = config.find("frames"); frames && !config.has("blocks"))
    forests.timing.blocks =
        std::min(defaults.blocks, std::max(1, config.convert<int>(*frames, "frames")));
  if (config.has("camera_path")) {
    std::filesystem::path path = config.get<std::string>("camera_path");
    if (path.is_relative() && !std::filesystem::exists(path) && !baseDirectory.empty())
      path = std::filesystem::path(baseDirectory) / path;
    forests.timing.path = readCameraPath(path.string());
  }
  readSection(config, forests, "forests");
  if (forests.timing.blocks > forests.timing.frames) {
    throwInputError("config {}: {} blocks need at least as many frames ({})",
                    config.keyPath("blocks"), forests.timing.blocks, forests.timing.frames);
  }
  return forests;
}

PoppingSettings parsePopping(ConfigObject& config) {
  PoppingSettings popping;
  popping.enabled = true;
  readSection(config, popping, "popping");
  if (popping.farDistance <= popping.nearDistance)
    throwInputError("config {}: must be greater than \"near\"", config.keyPath("far"));
  return popping;
}

BudgetSettings parseBudget(ConfigObject& config) {
  BudgetSettings budget;
  readSection(config, budget, "budget");
  if ((budget.memoryMb > 0.0) == (budget.psnrDb > 0.0)) {
    throwInputError(R"(config {}: give exactly one of "memory_mb" or "psnr_db" (> 0))",
                    config.path());
  }
  return budget;
}

}  // namespace

namespace {

// "trees": each a preset, a file or a capture folder (broadleaf without the key), labels unique.
std::vector<TreeSpec> parseTrees(ConfigObject& config, const std::string& baseDirectory) {
  std::vector<TreeSpec> trees;
  if (config.has("trees")) {
    if (config.require("trees") == nlohmann::json::array())
      throwInputError("config trees: an empty list runs nothing (leave the key out for broadleaf)");
    for (ConfigObject& tree : config.children("trees"))
      trees.push_back(parseTreeSpec(tree, baseDirectory));
  } else {
    TreeSpec spec;
    spec.preset = "broadleaf";
    trees.push_back(spec);
  }
  std::set<std::string> labels;
  for (const TreeSpec& tree : trees) {
    const std::string label = tree.label();
    if (label.empty() || label == "." || label == "..")
      throwInputError("config trees: '{}' is no name for a results folder (give it a \"name\")",
                      label);
    if (!labels.insert(label).second)
      throwInputError("config trees: '{}' appears twice (give one a \"name\")", tree.label());
  }
  return trees;
}

// "methods": each entry's sweep expanded into variants, every point validated now so a bad
// value fails before hours of work (every registered method without the key).
std::vector<MethodVariant> parseMethods(ConfigObject& config) {
  std::vector<MethodVariant> variants;
  if (config.has("methods")) {
    if (config.require("methods") == nlohmann::json::array())
      throwInputError(
          "config methods: an empty list runs nothing (leave the key out for every method)");
    for (ConfigObject& entry : config.children("methods")) {
      const std::string method = entry.get<std::string>("method");
      const MethodInfo& info = builtinMethods().find(method);
      const nlohmann::json* params = entry.find("params");
      if (params && !params->is_object())
        throwInputError("config {}: expected an object", entry.keyPath("params"));
      entry.finish("a method entry");
      for (const nlohmann::json& point : expandSweep(params ? *params : nlohmann::json::object())) {
        info.create(point, entry.keyPath("params"));
        variants.push_back({method, point, variantLabel(method, point)});
      }
    }
  } else {
    for (const std::string& name : builtinMethods().names())
      variants.push_back({name, nlohmann::json::object(), name});
  }
  std::set<std::string> labels;
  for (const MethodVariant& variant : variants) {
    if (!labels.insert(variant.label).second)
      throwInputError("config methods: '{}' appears twice", variant.label);
  }
  return variants;
}

// The sections after trees and methods: views (with close-ups), forests, popping, budget.
void parseSections(ConfigObject& config, ExperimentConfig& experiment,
                   const std::string& baseDirectory) {
  if (config.has("views")) {
    ConfigObject views = config.child("views");
    CloseupSettings closeups;
    if (views.has("closeups")) {
      ConfigObject section = views.child("closeups");
      closeups = parseCloseups(section);
    }
    experiment.views = parseViews(views);
    experiment.views.closeups = closeups;
  }
  if (config.has("forests")) {
    ConfigObject forests = config.child("forests");
    experiment.forests = parseForests(forests, experiment.views.render, baseDirectory);
  } else {
    experiment.forests.timing.width = experiment.views.render.width;
    experiment.forests.timing.height = experiment.views.render.height;
  }
  if (config.has("popping")) {
    ConfigObject popping = config.child("popping");
    experiment.popping = parsePopping(popping);
  }
  if (config.has("budget")) {
    ConfigObject budget = config.child("budget");
    experiment.budget = parseBudget(budget);
  }
}

}  // namespace

ExperimentConfig parseExperimentConfig(const nlohmann::json& json,
                                       const std::string& baseDirectory) {
  ExperimentConfig experiment;
  experiment.raw = json;
  experiment.hash = hashJson(json);
  ConfigObject config(json, "");
  experiment.name = checkPathComponent(config.get<std::string>("name"), "config name");
  int64_t seed = 1;
  ParamReader reader(config, "config");
  reader("seed", seed, int64_t(0), int64_t(1) << 53, "every random choice of the run");
  experiment.seed = static_cast<uint64_t>(seed);
  experiment.trees = parseTrees(config, baseDirectory);
  experiment.variants = parseMethods(config);
  parseSections(config, experiment, baseDirectory);
  config.finish();
  return experiment;
}

ExperimentConfig readExperimentConfig(const std::string& path) {
  const nlohmann::json json = readJsonFile(path);
  try {
    return parseExperimentConfig(json, std::filesystem::path(path).parent_path().string());
  } catch (const InputError& error) {
    throw InputError(path + ": " + error.what());
  }
}

}  // namespace canopy
