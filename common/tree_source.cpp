#include "common/tree_source.h"

#include <filesystem>

#include <nlohmann/json.hpp>

#include "common/captures.h"
#include "common/file_checks.h"
#include "common/lsystem.h"

namespace canopy {

std::string TreeSpec::label() const {
  if (!name.empty()) return name;
  if (kind == Kind::kFile) return std::filesystem::path(file.path).stem().string();
  if (kind == Kind::kCaptures)
    return std::filesystem::path(captures).lexically_normal().filename().string();
  std::string label = preset + "_s" + std::to_string(seed);
  if (leaves > 0) label += "_l" + std::to_string(leaves);
  return label;
}

nlohmann::json TreeSpec::source() const {
  if (kind == Kind::kCaptures) return {{"captures", captures}};
  if (kind == Kind::kFile) {
    return {{"file", file.path}, {"leaf_materials", file.leafMaterials}, {"up", file.up}};
  }
  nlohmann::json source = {{"preset", preset}, {"seed", seed}};
  if (leaves > 0) source["leaves"] = leaves;
  return source;
}

TreeSpec parseTreeSpec(ConfigObject& config, const std::string& baseDirectory) {
  TreeSpec spec;
  spec.name = config.get<std::string>("name", "");
  if (!spec.name.empty()) checkPathComponent(spec.name, "config " + config.keyPath("name"));
  const bool hasPreset = config.has("preset"), hasFile = config.has("file"),
             hasCaptures = config.has("captures");
  if (int(hasPreset) + int(hasFile) + int(hasCaptures) != 1) {
    throwInputError(R"(config {}: a tree needs exactly one of "preset", "file" or "captures")",
                    config.path());
  }
  if (hasCaptures) {
    spec.kind = TreeSpec::Kind::kCaptures;
    std::filesystem::path path = config.get<std::string>("captures");
    if (path.is_relative() && !baseDirectory.empty() && !pathExists(path))
      path = std::filesystem::path(baseDirectory) / path;
    spec.captures = path.string();
  } else if (hasPreset) {
    spec.kind = TreeSpec::Kind::kPreset;
    spec.preset = config.get<std::string>("preset");
    treePreset(spec.preset);  // validates the name
    const auto seed = config.get<int64_t>("seed", 1);
    if (seed < 0) throwInputError("config {}: seed must be >= 0", config.keyPath("seed"));
    spec.seed = static_cast<uint64_t>(seed);
    spec.leaves = config.get<int>("leaves", 0);
    if (spec.leaves < 0 || spec.leaves > 2'000'000) {
      throwInputError("config {}: {} is out of range [1, 2000000]", config.keyPath("leaves"),
                      spec.leaves);
    }
  } else {
    spec.kind = TreeSpec::Kind::kFile;
    std::filesystem::path path = config.get<std::string>("file");
    if (path.is_relative() && !baseDirectory.empty() && !pathExists(path)) {
      path = std::filesystem::path(baseDirectory) / path;
    }
    spec.file.path = path.string();
    spec.file.leafMaterials = config.get<std::vector<std::string>>("leaf_materials", {});
    spec.file.up = config.get<std::string>("up", "y");
    if (spec.file.up != "y" && spec.file.up != "z") {
      throwInputError(R"(config {}: '{}' must be "y" or "z")", config.keyPath("up"), spec.file.up);
    }
  }
  config.finish("a tree");
  return spec;
}

Tree loadTree(const TreeSpec& spec) {
  Tree tree;
  if (spec.kind == TreeSpec::Kind::kCaptures) {
    auto captures = std::make_shared<CaptureSet>(readNerfCaptures(spec.captures));
    tree.bounds = captures->bounds;
    tree.captures = std::move(captures);
  } else if (spec.kind == TreeSpec::Kind::kPreset) {
    LSystemTreeParams params = treePreset(spec.preset);
    if (spec.leaves > 0) params.leaves = spec.leaves;
    tree = generateTree(params, spec.seed);
  } else {
    tree = loadTreeFile(spec.file);
  }
  tree.name = spec.label();
  return tree;
}

}  // namespace canopy
