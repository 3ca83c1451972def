#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace canopy {

// `canopy-bench slurm`: an experiment as a Slurm job array (one task per shard of the cost
// plan) and a merge job that depends on it.
struct SlurmOptions {
  std::filesystem::path config;           // the experiment config
  int shards = 1;                         // array tasks, one shard each
  std::filesystem::path out;              // the run folder the merge fills
  std::string partition;                  // empty: the cluster's default partition
  std::string time = "02:00:00";          // wall-clock limit of each task (sbatch --time)
  int cpusPerTask = 2;                    // also llvmpipe's thread count
  int gpusPerTask = 0;                    // > 0: --gpus-per-task (use with --gl egl)
  std::string gl = "osmesa";              // the backend the tasks render with
  std::string account;                    // empty: the user's default account
  bool submit = false;                    // call sbatch, else print the commands
  std::filesystem::path benchExecutable;  // the canopy-bench the tasks run (this one)
};

// What writeSlurmJobs wrote into `out`.
struct SlurmJobFiles {
  std::filesystem::path plan;         // plan.json: the shards, their units and expected costs
  std::filesystem::path arrayScript;  // canopy-array.sbatch
  std::filesystem::path mergeScript;  // canopy-merge.sbatch
  std::filesystem::path logs;         // logs/: shard-<K>.out/.err, merge.out/.err
};

// Writes the plan and both scripts into options.out (InputError for a bad config, shard count
// or option, naming it); with options.submit, submits the array, then the merge with
// --dependency=afterok on it, and prints both job ids; otherwise prints the sbatch commands.
SlurmJobFiles writeSlurmJobs(const SlurmOptions& options);
void runSlurmCommand(const SlurmOptions& options);

// What the merge of a planned run checks: every shard folder of `plan` holds a finished run of
// that shard and config; InputError naming the first shard that does not, with the sbatch line
// that reruns it alone. Returns the shard folders in order.
std::vector<std::filesystem::path> completeShardFolders(const std::filesystem::path& plan);

}  // namespace canopy
