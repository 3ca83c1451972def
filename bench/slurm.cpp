#include "bench/slurm.h"

#include <cstdio>
#include <regex>

#include <fmt/format.h>

#include "bench/experiment.h"
#include "bench/run_meta.h"
#include "bench/shard_plan.h"
#include "common/atomic_file.h"
#include "common/config.h"
#include "common/error.h"
#include "common/file_checks.h"
#include "common/json_fields.h"
#include "common/subprocess.h"

namespace canopy {
namespace {

namespace fs = std::filesystem;

// A word for a POSIX shell, single-quoted ('it'\''s').
std::string shellQuoted(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// Values that end up on #SBATCH lines must be one plain word: a newline or a space there would
// silently drop or change a directive.
void checkSlurmWord(const std::string& option, const std::string& value, const std::regex& form,
                    const char* example) {
  if (!std::regex_match(value, form))
    throwInputError("{}: '{}' is not a valid value (e.g. {})", option, shortened(value), example);
}

void checkOptions(const SlurmOptions& options) {
  if (options.shards < 1 || options.shards > 10000)
    throwInputError("--shards: {} must be within [1, 10000]", options.shards);
  if (options.cpusPerTask < 1 || options.cpusPerTask > 4096)
    throwInputError("--cpus-per-task: {} must be within [1, 4096]", options.cpusPerTask);
  if (options.gpusPerTask < 0 || options.gpusPerTask > 64)
    throwInputError("--gpus-per-task: {} must be within [0, 64]", options.gpusPerTask);
  if (options.gl != "osmesa" && options.gl != "egl") {
    throwInputError("--gl: '{}' is not a headless backend; use egl (GPU nodes) or osmesa",
                    shortened(options.gl));
  }
  if (options.gpusPerTask > 0 && options.gl != "egl")
    throwInputError("--gpus-per-task: {} GPU(s) need --gl egl to be used", options.gpusPerTask);
  // Slurm's time formats: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S.
  checkSlurmWord("--time", options.time, std::regex(R"((\d{1,5}-)?\d{1,5}(:\d{1,2}){0,2})"),
                 "02:00:00 or 1-12:00:00");
  const std::regex name(R"([A-Za-z0-9_.,+-]{1,128})");
  if (!options.partition.empty())
    checkSlurmWord("--partition", options.partition, name, "gpu or cpu,long");
  if (!options.account.empty()) checkSlurmWord("--account", options.account, name, "lab42");
}

// One #SBATCH line per directive the user gave; the ones left out take the cluster's defaults.
std::string optionalDirectives(const SlurmOptions& options) {
  std::string lines;
  if (!options.partition.empty()) lines += "#SBATCH --partition=" + options.partition + "\n";
  if (!options.account.empty()) lines += "#SBATCH --account=" + options.account + "\n";
  return lines;
}

std::string arrayScript(const SlurmOptions& options, const ExperimentConfig& config,
                        const SlurmJobFiles& files, const fs::path& out) {
  const int n = options.shards;
  std::string gpus;
  if (options.gpusPerTask > 0)
    gpus = fmt::format("#SBATCH --gpus-per-task={}\n", options.gpusPerTask);
  return fmt::format(
      R"(#!/bin/bash
# Canopy benchmark "{name}" as a Slurm job array: one task per shard, {n} shards.
# Written by `canopy-bench slurm` from {config}
# (config hash {hash}); {plan} lists what each shard runs and its expected cost.
#
# Task K runs shard K/{n} into {out}/shards/K. A task that failed or was cancelled can be
# rerun alone, and resumes what it had finished:
#   sbatch --array=K {script}
# {merge} joins the shards into {out} once every task has succeeded.
#SBATCH --job-name=canopy-{name}
#SBATCH --array=0-{last}
#SBATCH --cpus-per-task={cpus}
#SBATCH --time={time}
#SBATCH --output={logs}/shard-%a.out
#SBATCH --error={logs}/shard-%a.err
{optional}{gpus}
set -euo pipefail

shard="${{SLURM_ARRAY_TASK_ID:?run this script with sbatch}}"
out={out_q}/shards/"${{shard}}"

# Without a GPU, llvmpipe renders with one thread per CPU Slurm gave the task.
export LP_NUM_THREADS="${{LP_NUM_THREADS:-${{SLURM_CPUS_PER_TASK:-1}}}}"

# On a GPU node, keep what the driver says in the shard's meta.json.
gpu_report=()
if command -v nvidia-smi >/dev/null 2>&1; then
  report={logs_q}/shard-"${{shard}}"-nvidia-smi.txt
  if nvidia-smi >"${{report}}" 2>&1; then gpu_report=(--gpu-report "${{report}}"); fi
fi

exec {bench} --config {config_q} --gl {gl} \
  --shard "${{shard}}/{n}" --out "${{out}}" --resume-or-fresh "${{gpu_report[@]}}"
)",
      fmt::arg("name", config.name), fmt::arg("n", n), fmt::arg("last", n - 1),
      fmt::arg("config", options.config.string()), fmt::arg("hash", config.hash),
      fmt::arg("plan", files.plan.string()), fmt::arg("out", out.string()),
      fmt::arg("script", files.arrayScript.string()), fmt::arg("merge", files.mergeScript.string()),
      fmt::arg("cpus", options.cpusPerTask), fmt::arg("time", options.time),
      fmt::arg("logs", files.logs.string()), fmt::arg("optional", optionalDirectives(options)),
      fmt::arg("gpus", gpus), fmt::arg("out_q", shellQuoted(out.string())),
      fmt::arg("logs_q", shellQuoted(files.logs.string())),
      fmt::arg("bench", shellQuoted(options.benchExecutable.string())),
      fmt::arg("config_q", shellQuoted(options.config.string())), fmt::arg("gl", options.gl));
}

std::string mergeScript(const SlurmOptions& options, const ExperimentConfig& config,
                        const SlurmJobFiles& files, const fs::path& out) {
  return fmt::format(
      R"(#!/bin/bash
# Joins the shards of the Canopy job array "{name}" into {out}.
# Submitted with --dependency=afterok:<array job id>, so it starts once every task succeeded.
# It refuses (exit 2), naming the shard and the sbatch line that reruns it, while a shard is
# missing or unfinished; after such a rerun, submit this script again.
#SBATCH --job-name=canopy-{name}-merge
#SBATCH --cpus-per-task=1
#SBATCH --time=00:30:00
#SBATCH --output={logs}/merge.out
#SBATCH --error={logs}/merge.err
{optional}
set -euo pipefail

exec {bench} merge {out_q} --plan {plan_q}
)",
      fmt::arg("name", config.name), fmt::arg("out", out.string()),
      fmt::arg("logs", files.logs.string()), fmt::arg("optional", optionalDirectives(options)),
      fmt::arg("bench", shellQuoted(options.benchExecutable.string())),
      fmt::arg("out_q", shellQuoted(out.string())),
      fmt::arg("plan_q", shellQuoted(files.plan.string())));
}

// `sbatch --parsable` prints "<job id>" or "<job id>;<cluster>".
std::string submit(const std::vector<std::string>& command) {
  const ProcessResult result = runProcess(command);
  std::smatch match;
  if (result.exitCode != 0 || !std::regex_search(result.output, match, std::regex(R"(^(\d+))"))) {
    std::string said = result.errors.empty() ? result.output : result.errors;
    while (!said.empty() && (said.back() == '\n' || said.back() == ' ')) said.pop_back();
    throwInputError("sbatch: {} (exit {}){}", command.back(), result.exitCode,
                    said.empty() ? "" : ": " + shortened(said));
  }
  return match[1];
}

}  // namespace

SlurmJobFiles writeSlurmJobs(const SlurmOptions& given) {
  checkOptions(given);
  SlurmOptions options = given;
  if (!regularFileExists(options.config))
    throwInputError("--config: {}: no such file", options.config.string());
  options.config = fs::absolute(options.config).lexically_normal();
  const ExperimentConfig config = readExperimentConfig(options.config.string());
  const ShardPlan plan = planShards(config, options.shards, "--shards");
  const fs::path out = fs::absolute(options.out).lexically_normal();
  // The logs' paths go on #SBATCH lines, which Slurm splits at white space and expands % in.
  if (out.string().find_first_of(" \t\n%") != std::string::npos)
    throwInputError("--out: '{}' has white space or '%', which #SBATCH lines cannot hold",
                    shortened(out.string()));
  fs::create_directories(out);
  SlurmJobFiles files{out / "plan.json", out / "canopy-array.sbatch", out / "canopy-merge.sbatch",
                      out / "logs"};
  fs::create_directories(files.logs);

  PlanFile planFile;
  planFile.experiment = config.name;
  planFile.configHash = config.hash;
  planFile.arrayScript = files.arrayScript.string();
  planFile.mergeScript = files.mergeScript.string();
  for (int s = 0; s < plan.shards; ++s) {
    PlanFile::Shard shard{s,
                          fmt::format("{}/{}", s, plan.shards),
                          (out / "shards" / std::to_string(s)).string(),
                          plan.expectedCost[size_t(s)],
                          {}};
    for (const ShardUnit& unit : plan.units[size_t(s)])
      shard.units.push_back({unit.treeLabel, unit.variantLabel, unit.expectedCost});
    planFile.shards.push_back(std::move(shard));
  }
  writeTextAtomically(files.plan, writeFields(planFile).dump(2) + "\n");
  writeTextAtomically(files.arrayScript, arrayScript(options, config, files, out));
  writeTextAtomically(files.mergeScript, mergeScript(options, config, files, out));
  for (const fs::path& script : {files.arrayScript, files.mergeScript}) {
    fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add);
  }
  return files;
}

void runSlurmCommand(const SlurmOptions& options) {
  const SlurmJobFiles files = writeSlurmJobs(options);
  std::printf("wrote %s, %s and %s (%d shards)\n", files.plan.c_str(), files.arrayScript.c_str(),
              files.mergeScript.c_str(), options.shards);
  if (!options.submit) {
    std::printf(
        "submit them with:\n  sbatch --parsable %s      # prints the array job id, ID\n"
        "  sbatch --dependency=afterok:ID --kill-on-invalid-dep=yes %s\n",
        files.arrayScript.c_str(), files.mergeScript.c_str());
    return;
  }
  const std::string array = submit({"sbatch", "--parsable", files.arrayScript.string()});
  const std::string merge = submit({"sbatch", "--parsable", "--dependency=afterok:" + array,
                                    "--kill-on-invalid-dep=yes", files.mergeScript.string()});
  std::printf(
      "array job %s (%d tasks), merge job %s after it; logs in %s\n"
      "a failed task K reruns alone with: sbatch --array=K %s\n"
      "then merge again with: sbatch --dependency=afterok:<its id> %s\n",
      array.c_str(), options.shards, merge.c_str(), files.logs.c_str(), files.arrayScript.c_str(),
      files.mergeScript.c_str());
}

std::vector<fs::path> completeShardFolders(const fs::path& planPath) {
  if (!regularFileExists(planPath)) throwInputError("--plan: {}: no such file", planPath.string());
  PlanFile plan;
  readFields(readJsonFile(planPath.string()), planPath.string(), plan);
  std::vector<fs::path> folders;
  const int n = static_cast<int>(plan.shards.size());
  for (const PlanFile::Shard& shard : plan.shards) {
    const fs::path folder = shard.folder;
    const std::string rerun =
        fmt::format("rerun it alone with: sbatch --array={} {}", shard.shard, plan.arrayScript);
    if (!regularFileExists(folder / "meta.json") || !regularFileExists(folder / "metrics.jsonl"))
      throwInputError("shard {} ({}): has no run yet; {}", shard.argument, folder.string(), rerun);
    const RunMeta meta = readRunMeta(folder);
    if (!meta.finished)
      throwInputError("shard {} ({}): its run is unfinished; {}", shard.argument, folder.string(),
                      rerun);
    const std::string heldShard = meta.shard.value.value_or("?");
    const std::string heldConfig = meta.configHash.value.value_or("?");
    if (heldShard != fmt::format("{}/{}", shard.shard, n) || heldConfig != plan.configHash) {
      throwInputError("shard {} ({}): holds shard {} of config {}, not of this plan ({}); {}",
                      shard.argument, folder.string(), heldShard, heldConfig, plan.configHash,
                      rerun);
    }
    folders.push_back(folder);
  }
  return folders;
}

}  // namespace canopy
