#pragma once

#include <filesystem>
#include <string>

#include "bench/experiment.h"
#include "bench/run_folder.h"
#include "common/gl/context.h"

namespace canopy {

struct RunOptions {
  std::filesystem::path outDirectory;  // results/<name> unless --out
  gl::Backend backend = gl::Backend::kOsMesa;
  int shardIndex = 0;  // --shard I/N: shard I of planShards(config, N), balanced by expected cost
  int shardCount = 1;
  std::filesystem::path gpuReport;  // --gpu-report: a file (e.g. nvidia-smi's) kept in meta.json
  bool saveImages = true;           // rendered views as PNG under images/
  bool saveAssets = true;           // baked assets under assets/ (their size is disk_bytes)
  ResumePolicy resume = ResumePolicy::kResume;  // what to do with a folder that holds a run
  bool printTable = true;  // the main table of the first tree on stdout at the end
};

// Runs a whole experiment: locks the output folder (RunFolder), loads trees, bakes every method
// variant, renders and scores every view against the polygonal reference, times every forest
// interleaved with it, appends each record as it is made (a resumed run skips records already
// present) and rewrites the summaries. The stages live in bench/stages.h.
void runExperiment(const ExperimentConfig& config, const RunOptions& options);

// "I/N" → (I, N); InputError naming --shard otherwise.
std::pair<int, int> parseShard(const std::string& text);

}  // namespace canopy
