#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "bench/experiment.h"

namespace canopy {

// One (tree × method variant) unit of an experiment: what a shard runs whole (its bake, views,
// forests and popping), with the cost it is expected to take.
struct ShardUnit {
  size_t tree = 0, variant = 0;  // indices into the config's trees and variants
  std::string treeLabel, variantLabel;
  double expectedCost = 0.0;  // ≈ seconds on llvmpipe (2 cores); only proportions matter
};

// The units of an experiment split into N shards of about equal expected cost: the longest
// units first, each to the shard with the least so far (ties: the lowest index). Deterministic
// for a config and N, so every `--shard I/N` run, the Slurm scripts and plan.json agree.
struct ShardPlan {
  int shards = 1;
  std::vector<std::vector<ShardUnit>> units;  // per shard, in config order
  std::vector<double> expectedCost;           // per shard, the sum of its units'

  bool runs(int shard, size_t tree, size_t variant) const;
};

// plan.json as canopy-bench slurm writes it and the merge of a planned run reads it back.
struct PlanFile {
  struct Unit {
    std::string tree, variant;
    double expectedCost = 0.0;
    template <class V>
    void visit(V& v) {
      v("tree", tree);
      v("variant", variant);
      v("expected_cost", expectedCost);
    }
  };
  struct Shard {
    int shard = 0;
    std::string argument;  // "--shard" value, "I/N"
    std::string folder;    // where its task writes (absolute)
    double expectedCost = 0.0;
    std::vector<Unit> units;
    template <class V>
    void visit(V& v) {
      v("shard", shard);
      v("argument", argument);
      v("folder", folder);
      v("expected_cost", expectedCost);
      v("units", units);
    }
  };
  std::string experiment, configHash;
  std::string costUnit = "about seconds on llvmpipe with 2 cores; only proportions matter";
  std::string arrayScript, mergeScript;  // absolute paths of the job scripts
  std::vector<Shard> shards;
  template <class V>
  void visit(V& v) {
    v("experiment", experiment);
    v("config_hash", configHash);
    v("cost_unit", costUnit);
    v("array_script", arrayScript);
    v("merge_script", mergeScript);
    v("shards", shards);
  }
};

// The expected cost of every unit, from the config alone (no tree is loaded): the tree's leaf
// count (a preset's, or estimated from a file's size, or a capture's image count) scales each
// method's CostHint over the views, forests, popping and budget search the config asks for.
std::vector<ShardUnit> experimentUnits(const ExperimentConfig& config);

// InputError naming `option` when `shards` is below 1 or above the number of units (a shard
// would have nothing to do).
ShardPlan planShards(const ExperimentConfig& config, int shards, const std::string& option);

}  // namespace canopy
