#pragma once

#include <filesystem>
#include <string>

#include "bench/experiment.h"
#include "common/gl/context.h"

namespace canopy {

struct RunOptions {
  std::filesystem::path outDirectory;  // results/<name> unless --out
  gl::Backend backend = gl::Backend::kOsMesa;
  int shardIndex = 0;  // --shard I/N: units u with u % N == I
  int shardCount = 1;
  bool saveImages = true;  // rendered views as PNG under images/
  bool saveAssets = true;  // baked assets under assets/ (their size is disk_bytes)
};

// Runs a whole experiment: loads trees, bakes every method variant, renders and scores every
// view against the polygonal reference, times every forest, appends each record as it is made
// (a rerun skips records already present) and rewrites the summaries.
void runExperiment(const ExperimentConfig& config, const RunOptions& options);

// "I/N" → (I, N); InputError naming --shard otherwise.
std::pair<int, int> parseShard(const std::string& text);

}  // namespace canopy
