#include "bench/experiment.h"

#include <cmath>
#include <filesystem>
#include <regex>
#include <set>

#include <fmt/format.h>

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

template <typename T>
std::vector<T> readList(ConfigObject& config, const std::string& key, std::vector<T> fallback, T lo,
                        T hi) {
  const nlohmann::json* value = config.find(key);
  if (!value) return fallback;
  if (!value->is_array()) throwInputError("config {}: expected a list", config.keyPath(key));
  std::vector<T> result;
  for (const nlohmann::json& item : *value) {
    const T v = config.convert<T>(item, key);
    if (!(v >= lo && v <= hi)) {
      throwInputError("config {}: value {} is out of range [{}, {}]", config.keyPath(key), v, lo,
                      hi);
    }
    result.push_back(v);
  }
  return result;
}

template <typename T>
T readNumber(ConfigObject& config, const std::string& key, T fallback, T lo, T hi) {
  const T value = config.get<T>(key, fallback);
  if (!(value >= lo && value <= hi)) {
    throwInputError("config {}: value {} is out of range [{}, {}]", config.keyPath(key), value, lo,
                    hi);
  }
  return value;
}

void readResolution(ConfigObject& config, int& width, int& height) {
  const auto resolution = readList<int>(config, "resolution", {width, height}, 16, 8192);
  if (resolution.size() != 2)
    throwInputError("config {}: expected [width, height]", config.keyPath("resolution"));
  width = resolution[0];
  height = resolution[1];
}

glm::vec3 readVec3(ConfigObject& config, const std::string& key, glm::vec3 fallback, float lo,
                   float hi) {
  const auto values = readList<float>(config, key, {fallback.x, fallback.y, fallback.z}, lo, hi);
  if (values.size() != 3) throwInputError("config {}: expected three numbers", config.keyPath(key));
  return {values[0], values[1], values[2]};
}

CloseupSettings parseCloseups(ConfigObject& config) {
  CloseupSettings closeups;
  closeups.enabled = true;
  closeups.distance = readNumber<float>(config, "distance", closeups.distance, 1.01f, 10000.0f);
  closeups.fovYDegrees = readNumber<float>(config, "fov_deg", closeups.fovYDegrees, 0.5f, 170.0f);
  closeups.azimuths = readNumber<int>(config, "azimuths", closeups.azimuths, 1, 360);
  closeups.elevations = readList<float>(config, "elevations", closeups.elevations, -90.0f, 90.0f);
  config.finish("views.closeups");
  return closeups;
}

ViewSettings parseViews(ConfigObject& config) {
  ViewSettings views;
  RenderSettings& render = views.render;
  readResolution(config, render.width, render.height);
  render.supersample = readNumber<int>(config, "supersample", 2, 1, 8);
  render.fovYDegrees = readNumber<float>(config, "fov_deg", 40.0f, 1.0f, 170.0f);
  const std::string shading = config.get<std::string>("shading", "unlit");
  if (shading != "unlit" && shading != "lit") {
    throwInputError("config {}: '{}' must be \"unlit\" or \"lit\"", config.keyPath("shading"),
                    shading);
  }
  render.shading = shading == "lit" ? Shading::kLit : Shading::kUnlit;
  render.background = readVec3(config, "background", render.background, 0.0f, 1.0f);
  render.lightDirection = readVec3(config, "light_direction", render.lightDirection, -1.0f, 1.0f);
  if (glm::length(render.lightDirection) < 1e-3f) {
    throwInputError("config {}: the light direction must not be zero",
                    config.keyPath("light_direction"));
  }
  render.ambient = readNumber<float>(config, "ambient", render.ambient, 0.0f, 1.0f);
  render.shadows = config.get<bool>("shadows", false);
  if (render.shadows && render.shading != Shading::kLit)
    throwInputError("config {}: shadows need \"shading\": \"lit\"", config.keyPath("shadows"));
  render.shadowMapSize =
      readNumber<int>(config, "shadow_map_size", render.shadowMapSize, 64, 16384);
  render.ambientOcclusion = config.get<bool>("ambient_occlusion", render.ambientOcclusion);
  render.flipPixelsPerDegree =
      readNumber<double>(config, "flip_ppd", render.flipPixelsPerDegree, 1.0, 1000.0);
  views.distances = readList<float>(config, "distances", views.distances, 1.01f, 10000.0f);
  views.elevations = readList<float>(config, "elevations", views.elevations, -90.0f, 90.0f);
  views.azimuths = readNumber<int>(config, "azimuths", views.azimuths, 1, 360);
  if (config.has("closeups")) {
    ConfigObject closeups = config.child("closeups");
    views.closeups = parseCloseups(closeups);
  }
  config.finish("views");
  return views;
}

// A camera path recorded by canopy-view: {"frames": [{"position", "target", "up", "fov_deg"}]}.
std::vector<Camera> readCameraPath(const std::string& path) {
  const nlohmann::json json = readJsonFile(path);
  std::vector<Camera> cameras;
  try {
    for (const auto& frame : json.at("frames")) {
      Camera c;
      const auto vec = [&](const char* key) {
        const auto& v = frame.at(key);
        return glm::vec3(v.at(0).get<float>(), v.at(1).get<float>(), v.at(2).get<float>());
      };
      c.position = vec("position");
      c.target = vec("target");
      c.up = vec("up");
      c.fovYDegrees = frame.at("fov_deg").get<float>();
      if (!std::isfinite(c.fovYDegrees) || c.fovYDegrees <= 1.0f || c.fovYDegrees >= 170.0f ||
          c.position == c.target)
        throwInputError("{}: frame {} is not a valid camera", path, cameras.size());
      cameras.push_back(c);
    }
  } catch (const nlohmann::json::exception& e) {
    throwInputError("{}: not a camera path ({})", path, e.what());
  }
  if (cameras.empty()) throwInputError("{}: a camera path needs frames", path);
  // Near/far planes from the path itself: the forest lies within it.
  for (Camera& c : cameras) {
    c.nearPlane = 0.05f;
    c.farPlane = 5000.0f;
  }
  return cameras;
}

ForestSettings parseForests(ConfigObject& config, const RenderSettings& render,
                            const std::string& baseDirectory) {
  ForestSettings forests;
  ForestTiming& timing = forests.timing;
  timing.width = render.width;
  timing.height = render.height;
  forests.sizes = readList<int>(config, "sizes", forests.sizes, 1, 1'000'000);
  timing.frames = readNumber<int>(config, "frames", timing.frames, 1, 100'000);
  timing.warmup = readNumber<int>(config, "warmup", timing.warmup, 0, 100'000);
  // Without "blocks", as many as the frames allow up to the default.
  timing.blocks =
      readNumber<int>(config, "blocks", std::min(timing.blocks, timing.frames), 1, 10'000);
  if (timing.blocks > timing.frames) {
    throwInputError("config {}: {} blocks need at least as many frames ({})",
                    config.keyPath("blocks"), timing.blocks, timing.frames);
  }
  readResolution(config, timing.width, timing.height);
  if (config.has("camera_path")) {
    std::filesystem::path path = config.get<std::string>("camera_path");
    if (path.is_relative() && !std::filesystem::exists(path) && !baseDirectory.empty())
      path = std::filesystem::path(baseDirectory) / path;
    timing.path = readCameraPath(path.string());
  }
  config.finish("forests");
  return forests;
}

PoppingSettings parsePopping(ConfigObject& config) {
  PoppingSettings popping;
  popping.enabled = true;
  popping.frames = readNumber<int>(config, "frames", popping.frames, 2, 10'000);
  popping.nearDistance = readNumber<float>(config, "near", popping.nearDistance, 1.01f, 10'000.0f);
  popping.farDistance = readNumber<float>(config, "far", popping.farDistance, 1.01f, 100'000.0f);
  if (popping.farDistance <= popping.nearDistance)
    throwInputError("config {}: must be greater than \"near\"", config.keyPath("far"));
  popping.elevation = readNumber<float>(config, "elevation", popping.elevation, -89.0f, 89.0f);
  popping.orbitDistance =
      readNumber<float>(config, "orbit_distance", popping.orbitDistance, 1.01f, 10'000.0f);
  readResolution(config, popping.width, popping.height);
  config.finish("popping");
  return popping;
}

BudgetSettings parseBudget(ConfigObject& config) {
  BudgetSettings budget;
  budget.memoryMb = readNumber<double>(config, "memory_mb", 0.0, 0.0, 1e6);
  budget.psnrDb = readNumber<double>(config, "psnr_db", 0.0, 0.0, 100.0);
  if ((budget.memoryMb > 0.0) == (budget.psnrDb > 0.0)) {
    throwInputError("config {}: give exactly one of \"memory_mb\" or \"psnr_db\" (> 0)",
                    config.path());
  }
  budget.tolerance = readNumber<double>(config, "tolerance", budget.tolerance, 0.001, 0.5);
  budget.maxSteps = readNumber<int>(config, "max_steps", budget.maxSteps, 2, 64);
  config.finish("budget");
  return budget;
}

}  // namespace

ExperimentConfig parseExperimentConfig(const nlohmann::json& json,
                                       const std::string& baseDirectory) {
  ExperimentConfig experiment;
  experiment.raw = json;
  experiment.hash = hashJson(json);
  ConfigObject config(json, "");
  experiment.name = config.get<std::string>("name");
  if (!std::regex_match(experiment.name, std::regex("[A-Za-z0-9_.-]+"))) {
    throwInputError("config name: '{}' may use only letters, digits, '_', '.', '-'",
                    experiment.name);
  }
  experiment.seed =
      static_cast<uint64_t>(readNumber<int64_t>(config, "seed", 1, 0, int64_t(1) << 53));
  if (config.has("trees")) {
    for (ConfigObject& tree : config.children("trees"))
      experiment.trees.push_back(parseTreeSpec(tree, baseDirectory));
  } else {
    TreeSpec spec;
    spec.preset = "broadleaf";
    experiment.trees.push_back(spec);
  }
  std::set<std::string> treeLabels;
  for (const TreeSpec& tree : experiment.trees) {
    if (!treeLabels.insert(tree.label()).second) {
      throwInputError("config trees: '{}' appears twice (give one a \"name\")", tree.label());
    }
  }
  if (config.has("methods")) {
    for (ConfigObject& entry : config.children("methods")) {
      const std::string method = entry.get<std::string>("method");
      const MethodInfo& info = builtinMethods().find(method);
      const nlohmann::json* params = entry.find("params");
      if (params && !params->is_object())
        throwInputError("config {}: expected an object", entry.keyPath("params"));
      entry.finish("a method entry");
      for (const nlohmann::json& point : expandSweep(params ? *params : nlohmann::json::object())) {
        // Validate every point now, so a bad value fails before hours of work.
        info.create(point, entry.keyPath("params"));
        experiment.variants.push_back({method, point, variantLabel(method, point)});
      }
    }
  } else {
    for (const std::string& name : builtinMethods().names())
      experiment.variants.push_back({name, nlohmann::json::object(), name});
  }
  std::set<std::string> labels;
  for (const MethodVariant& variant : experiment.variants) {
    if (!labels.insert(variant.label).second)
      throwInputError("config methods: '{}' appears twice", variant.label);
  }
  if (config.has("views")) {
    ConfigObject views = config.child("views");
    experiment.views = parseViews(views);
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
