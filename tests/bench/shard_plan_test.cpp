// The cost-balanced shard plan and the Slurm job files written from it (no cluster needed; the
// real Slurm run is tests/slurm/slurm_cluster_test.sh, label "slurm").
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>

#include "bench/experiment.h"
#include "bench/shard_plan.h"
#include "bench/slurm.h"
#include "common/atomic_file.h"
#include "common/error.h"
#include "test_support.h"

namespace canopy {
namespace {

ExperimentConfig configOf(const std::string& text) {
  return parseExperimentConfig(nlohmann::json::parse(text), ".");
}

// Units of very different costs: a big tree with the slow volumetric bake, small trees with
// cheap methods.
const char* kUnevenConfig = R"({"name": "uneven",
  "trees": [{"preset": "broadleaf", "seed": 1}, {"preset": "sparse", "seed": 1},
            {"preset": "shrub", "seed": 1}],
  "methods": [{"method": "polygonal"}, {"method": "volumetric_opacity"},
              {"method": "billboard_cloud", "params": {"clusters": [50, 100]}}]})";

TEST(ShardPlan, EveryUnitRunsInExactlyOneShardAndTheShardsAreBalanced) {
  const ExperimentConfig config = configOf(kUnevenConfig);
  const std::vector<ShardUnit> units = experimentUnits(config);
  ASSERT_EQ(units.size(), 3u * 4u);
  double largest = 0.0;
  for (const ShardUnit& unit : units) {
    EXPECT_GT(unit.expectedCost, 0.0) << unit.treeLabel << " " << unit.variantLabel;
    largest = std::max(largest, unit.expectedCost);
  }
  for (int n : {1, 2, 3, 5, 12}) {
    const ShardPlan plan = planShards(config, n, "--shards");
    std::map<std::pair<size_t, size_t>, int> seen;
    for (int s = 0; s < n; ++s) {
      EXPECT_FALSE(plan.units[size_t(s)].empty()) << "shard " << s << " of " << n;
      for (const ShardUnit& unit : plan.units[size_t(s)]) {
        ++seen[{unit.tree, unit.variant}];
        EXPECT_TRUE(plan.runs(s, unit.tree, unit.variant));
      }
    }
    EXPECT_EQ(seen.size(), units.size());
    for (const auto& [unit, count] : seen) EXPECT_EQ(count, 1);
    // Longest-first greedy: no shard exceeds the lightest by more than one unit's cost.
    const auto [lightest, heaviest] =
        std::minmax_element(plan.expectedCost.begin(), plan.expectedCost.end());
    EXPECT_LE(*heaviest - *lightest, largest + 1e-9) << n << " shards";
  }
  // The volumetric bake of the 20,000-leaf tree is the most expensive unit of this config.
  const auto top = std::max_element(units.begin(), units.end(), [](const auto& a, const auto& b) {
    return a.expectedCost < b.expectedCost;
  });
  EXPECT_EQ(top->treeLabel, "broadleaf_s1");
  EXPECT_EQ(top->variantLabel, "volumetric_opacity");
}

TEST(ShardPlan, IsTheSameForTheSameConfigAndRefusesEmptyShards) {
  const ExperimentConfig config = configOf(kUnevenConfig);
  const ShardPlan a = planShards(config, 4, "--shard"), b = planShards(config, 4, "--shard");
  for (size_t s = 0; s < 4; ++s) {
    ASSERT_EQ(a.units[s].size(), b.units[s].size());
    for (size_t u = 0; u < a.units[s].size(); ++u) {
      EXPECT_EQ(a.units[s][u].tree, b.units[s][u].tree);
      EXPECT_EQ(a.units[s][u].variant, b.units[s][u].variant);
    }
  }
  try {
    planShards(config, 13, "--shards");
    FAIL() << "13 shards of 12 units accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("--shards"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("12"), std::string::npos) << error.what();
  }
}

SlurmOptions slurmOptions(const test::TempDir& dir) {
  test::writeText(dir / "small.json", R"({"name": "small",
    "trees": [{"preset": "sparse", "seed": 3, "leaves": 300}],
    "methods": [{"method": "polygonal"}, {"method": "billboard_cloud"},
                {"method": "single_leaf_indirect"}]})");
  SlurmOptions options;
  options.config = dir / "small.json";
  options.shards = 3;
  options.out = dir / "run";
  options.benchExecutable = "/opt/canopy/bin/canopy-bench";
  return options;
}

TEST(Slurm, WritesAReadableArrayScriptAMergeScriptAndThePlan) {
  test::TempDir dir;
  SlurmOptions options = slurmOptions(dir);
  options.partition = "gpu";
  options.gpusPerTask = 1;
  options.gl = "egl";
  options.time = "1-12:00:00";
  const SlurmJobFiles files = writeSlurmJobs(options);
  const std::string array = test::readText(files.arrayScript);
  for (const char* line : {"#!/bin/bash", "#SBATCH --array=0-2\n", "#SBATCH --partition=gpu\n",
                           "#SBATCH --gpus-per-task=1\n", "#SBATCH --time=1-12:00:00\n",
                           "--shard \"${shard}/3\"", "--gl egl", "--resume-or-fresh",
                           "'/opt/canopy/bin/canopy-bench'", "nvidia-smi", "sbatch --array=K"}) {
    EXPECT_NE(array.find(line), std::string::npos) << line << "\n" << array;
  }
  EXPECT_EQ(array.find("--account"), std::string::npos) << "no account given, none written";
  const std::string merge = test::readText(files.mergeScript);
  EXPECT_NE(merge.find(" merge "), std::string::npos) << merge;
  EXPECT_NE(merge.find("--plan"), std::string::npos) << merge;
  const nlohmann::json plan = nlohmann::json::parse(test::readText(files.plan));
  ASSERT_EQ(plan.at("shards").size(), 3u);
  EXPECT_EQ(plan.at("shards")[1].at("argument"), "1/3");
  EXPECT_TRUE(std::filesystem::is_directory(files.logs));
}

TEST(Slurm, BadOptionsAreInputErrorsNamingTheOption) {
  const std::vector<std::pair<std::string, std::function<void(SlurmOptions&)>>> cases = {
      {"--time", [](SlurmOptions& o) { o.time = "2 hours"; }},
      {"--partition", [](SlurmOptions& o) { o.partition = "gpu\n#SBATCH --mem=1"; }},
      {"--account", [](SlurmOptions& o) { o.account = "a b"; }},
      {"--gl", [](SlurmOptions& o) { o.gl = "glfw"; }},
      {"--gpus-per-task", [](SlurmOptions& o) { o.gpusPerTask = 1; }},  // with osmesa
      {"--cpus-per-task", [](SlurmOptions& o) { o.cpusPerTask = 0; }},
      {"--shards", [](SlurmOptions& o) { o.shards = 4; }},  // the config has 3 units
      {"--config", [](SlurmOptions& o) { o.config = "/nonexistent/x.json"; }},
      {"--out", [](SlurmOptions& o) { o.out = o.out / "with space"; }},
  };
  for (const auto& [option, spoil] : cases) {
    test::TempDir dir;
    SlurmOptions options = slurmOptions(dir);
    spoil(options);
    try {
      writeSlurmJobs(options);
      ADD_FAILURE() << option << ": accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(option), std::string::npos) << error.what();
    }
  }
}

TEST(Slurm, MergeOfAPlanNamesTheShardThatIsMissingOrUnfinished) {
  test::TempDir dir;
  const SlurmJobFiles files = writeSlurmJobs(slurmOptions(dir));
  const nlohmann::json plan = nlohmann::json::parse(test::readText(files.plan));
  const auto expectRefusal = [&](const std::string& words) {
    try {
      completeShardFolders(files.plan);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(words), std::string::npos) << what;
      EXPECT_NE(what.find("sbatch --array="), std::string::npos) << what;
    }
  };
  expectRefusal("shard 0/3");
  // A shard folder holding a run of shard `held` ("I/N"), finished or not.
  const auto writeRun = [&](int s, const std::string& held, bool finished) {
    const std::filesystem::path folder =
        plan.at("shards")[size_t(s)].at("folder").get<std::string>();
    nlohmann::json meta = {{"experiment", "small"},
                           {"config_hash", plan.at("config_hash")},
                           {"shard", held},
                           {"gl", {{"renderer", "test"}}}};
    if (finished) meta["finished"] = "2026-12-01T00:00:00Z";
    test::writeText(folder / "meta.json", meta.dump());
    test::writeText(folder / "metrics.jsonl", "");
  };
  // Shards 0 and 2 finished, shard 1 started but never finished (its task was killed).
  for (int s : {0, 1, 2}) writeRun(s, std::to_string(s) + "/3", s != 1);
  expectRefusal("shard 1/3");
  expectRefusal("sbatch --array=1 ");
  // A finished run of another shard count in its place is refused too.
  writeRun(1, "1/4", true);
  expectRefusal("holds shard 1/4");
  writeRun(1, "1/3", true);
  EXPECT_EQ(completeShardFolders(files.plan).size(), 3u);
}

}  // namespace
}  // namespace canopy
