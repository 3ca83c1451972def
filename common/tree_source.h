#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "common/config.h"
#include "common/tree.h"
#include "common/tree_loader.h"

namespace canopy {

// Where a tree comes from, as a config names it:
//   {"preset": "broadleaf", "seed": 1, "leaves": 20000}
//   {"file": "assets/oak.glb", "leaf_materials": ["Leaves"], "up": "y"}
//   {"captures": "captures/oak"}  (a NeRF-layout folder of calibrated RGBA photographs)
struct TreeSpec {
  enum class Kind { kPreset, kFile, kCaptures };
  Kind kind = Kind::kPreset;
  std::string preset;    // kPreset: broadleaf | shrub | sparse
  uint64_t seed = 1;     // kPreset: L-system seed
  int leaves = 0;        // kPreset: leaf count override (0: the preset's)
  TreeFileOptions file;  // kFile
  std::string captures;  // kCaptures: the folder
  std::string name;      // the label in results (default: preset or file stem)

  // A label unique within an experiment: "broadleaf_s1", "broadleaf_s1_l100000", "oak".
  std::string label() const;
  nlohmann::json source() const;  // for the kind:"tree" record
};

// Parses one entry of the config's "trees" list; `baseDirectory` resolves relative file paths.
TreeSpec parseTreeSpec(ConfigObject& config, const std::string& baseDirectory);

Tree loadTree(const TreeSpec& spec);

}  // namespace canopy
