// canopy-bench: runs an experiment config and writes results/<name>/.
// Exit codes: 0 success, 2 bad input or config (one line on stderr), 1 internal error.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "bench/capture_export.h"
#include "bench/experiment.h"
#include "bench/merge.h"
#include "bench/render_from_assets.h"
#include "bench/report.h"
#include "bench/results_store.h"
#include "bench/run_meta.h"
#include "bench/runner.h"
#include "bench/slurm.h"
#include "common/command_line.h"
#include "common/error.h"
#include "common/progress.h"
#include "common/tree_export.h"
#include "common/tree_source.h"
#include "methods/method.h"

namespace canopy {
namespace {

// A built-in tree as the export commands name it.
TreeSpec presetSpec(const std::string& preset, int64_t seed, int leaves) {
  if (seed < 0 || leaves < 0) throwInputError("--seed, --leaves: must be >= 0");
  TreeSpec spec;
  spec.preset = preset;
  spec.seed = static_cast<uint64_t>(seed);
  spec.leaves = leaves;
  return spec;
}

// The main command: run a config.
struct RunCommand {
  std::string config, out, backend = "osmesa", shard = "0/1", gpuReport;
  bool quiet = false, noImages = false, fresh = false, resumeOrFresh = false;
  bool listMethods = false, markdown = false;

  void add(CLI::App& app) {
    app.add_option("--config", config, "experiment config (JSON)");
    app.add_option("--out", out, "output folder (default: results/<config name>)");
    app.add_option("--gl", backend, "OpenGL backend: osmesa | egl | glfw");
    app.add_option("--shard", shard,
                   "run shard I of N of the (tree × method) units (balanced by expected cost), "
                   "as I/N");
    app.add_option("--gpu-report", gpuReport,
                   "a text file (e.g. nvidia-smi's output) to keep in meta.json");
    app.add_flag("--quiet", quiet, "no progress bars and no info logs");
    app.add_flag("--no-images", noImages, "do not write rendered views as PNG");
    app.add_flag("--fresh", fresh, "move an earlier run in the output folder aside and start anew");
    app.add_flag("--resume-or-fresh", resumeOrFresh,
                 "resume an unfinished run of the same config and code, else start anew "
                 "(make bench)");
    app.add_flag("--list-methods", listMethods,
                 "print every registered method, its description and its parameters, and exit");
    app.add_flag("--markdown", markdown,
                 "with --list-methods: the parameter tables of docs/METHODS.md");
  }

  int run() const {
    if (config.empty()) throwInputError("--config: required (e.g. --config configs/default.json)");
    const ExperimentConfig experiment = readExperimentConfig(config);
    RunOptions options;
    options.backend = gl::parseBackend(backend);
    std::tie(options.shardIndex, options.shardCount) = parseShard(shard);
    options.outDirectory = out.empty() ? std::filesystem::path("results") / experiment.name
                                       : std::filesystem::path(out);
    options.saveImages = !noImages;
    options.gpuReport = gpuReport;
    if (fresh && resumeOrFresh) throwInputError("--fresh and --resume-or-fresh exclude each other");
    options.resume = fresh           ? ResumePolicy::kFresh
                     : resumeOrFresh ? ResumePolicy::kResumeOrFresh
                                     : ResumePolicy::kResume;
    options.printTable = !quiet;
    runExperiment(experiment, options);
    return kExitOk;
  }
};

// --list-methods: each method's line and its parameters (as text, or Markdown for the docs).
int listMethods(bool markdown) {
  for (const std::string& name : builtinMethods().names()) {
    const MethodInfo& info = builtinMethods().find(name);
    if (markdown) {
      std::printf("<!-- parameters:%s -->\n%s<!-- /parameters -->\n\n", name.c_str(),
                  parameterTableMarkdown(info).c_str());
    } else {
      std::printf("%s: %s\n%s\n", name.c_str(), info.description.c_str(),
                  parameterTableText(info).c_str());
    }
  }
  return kExitOk;
}

// The largest seed a config accepts (integers beyond 2^53 do not survive JSON as doubles).
constexpr int64_t kMaxSeed = int64_t(1) << 53;

struct ExportTreeCommand {
  CLI::App* app = nullptr;
  std::string preset = "broadleaf", out;
  int64_t seed = 1;
  int leaves = 0;

  void add(CLI::App& parent) {
    app = parent.add_subcommand("export-tree", "write a built-in tree as OBJ + MTL + PNG");
    app->add_option("--preset", preset, "broadleaf | shrub | sparse");
    app->add_option("--seed", seed, "L-system seed")->check(CLI::Range(int64_t(0), kMaxSeed));
    app->add_option("--leaves", leaves, "leaf count (0: the preset's)")
        ->check(CLI::Range(0, 2'000'000));
    app->add_option("--out", out, "output folder")->required();
  }

  int run() const {
    std::printf("%s\n",
                exportTreeObj(loadTree(presetSpec(preset, seed, leaves)), out).string().c_str());
    return kExitOk;
  }
};

struct ExportCapturesCommand {
  CLI::App* app = nullptr;
  std::string preset = "broadleaf", out;
  int64_t seed = 1;
  int leaves = 0;
  CaptureExportOptions options;

  void add(CLI::App& parent) {
    app = parent.add_subcommand("export-captures",
                                "photograph a built-in tree into a NeRF-layout capture folder");
    app->add_option("--preset", preset, "broadleaf | shrub | sparse");
    app->add_option("--seed", seed, "L-system seed")->check(CLI::Range(int64_t(0), kMaxSeed));
    app->add_option("--leaves", leaves, "leaf count (0: the preset's)")
        ->check(CLI::Range(0, 2'000'000));
    app->add_option("--train", options.trainViews, "training views")->check(CLI::Range(2, 10000));
    app->add_option("--test", options.testViews, "held-out test views")
        ->check(CLI::Range(1, 10000));
    app->add_option("--resolution", options.resolution, "pixels per side")
        ->check(CLI::Range(16, 4096));
    app->add_option("--distance", options.distance, "camera distance in bounding radii")
        ->check(CLI::Range(1.1f, 1000.0f));
    app->add_option("--out", out, "output folder")->required();
  }

  int run(const std::string& backend) const {
    // CLI::Range lets NaN through (every comparison with it is false).
    if (!std::isfinite(options.distance)) throwInputError("--distance: must be a finite number");
    exportCaptures(loadTree(presetSpec(preset, seed, leaves)), out, options,
                   gl::parseBackend(backend));
    std::printf("%s\n", out.c_str());
    return kExitOk;
  }
};

// render --config C --tree T --variant V --view K --image PNG [--run RUN]: one view from a saved
// asset, without baking.
struct RenderCommand {
  CLI::App* app = nullptr;
  RenderFromAssetsRequest request;
  std::string runFolder;

  void add(CLI::App& parent) {
    app = parent.add_subcommand("render",
                                "draw one view of a variant from the asset a run saved (no bake)");
    app->add_option("--config", request.config, "the run's experiment config")->required();
    app->add_option("--run", runFolder, "the run folder (default: results/<config name>)");
    app->add_option("--tree", request.tree, "tree label, as in the run's records")->required();
    app->add_option("--variant", request.variant, "variant label, as in the run's records")
        ->required();
    app->add_option("--view", request.view, "view key, as in the run's records (d4_e30_a0)")
        ->required();
    app->add_option("--image", request.image, "PNG to write")->required();
  }

  int run(const std::string& backend) {
    request.run = runFolder;
    request.backend = gl::parseBackend(backend);
    renderFromAssets(request);
    std::printf("%s\n", request.image.c_str());
    return kExitOk;
  }
};

// report RUN...: rewrites summaries (md, csv, tex, popping.csv) from metrics.jsonl.
struct ReportCommand {
  CLI::App* app = nullptr;
  std::vector<std::string> runs;

  void add(CLI::App& parent) {
    app = parent.add_subcommand("report", "rewrite a run's summaries from its metrics.jsonl");
    app->add_option("runs", runs, "run folders")->required();
  }

  int run() const {
    for (const std::string& run : runs) {
      const std::filesystem::path folder(run);
      if (!std::filesystem::exists(folder / "metrics.jsonl"))
        throwInputError("{}: no metrics.jsonl (not a run folder)", run);
      const RunMeta meta = readRunMeta(folder);
      writeSummaries(folder, ResultsStore::readRecords(folder / "metrics.jsonl"), meta.experiment,
                     meta.gl.renderer);
      std::printf("%s\n", run.c_str());
    }
    return kExitOk;
  }
};

// merge OUT RUN... | merge OUT --plan PLAN: joins shard outputs.
struct MergeCommand {
  CLI::App* app = nullptr;
  std::string out, plan;
  std::vector<std::string> inputs;

  void add(CLI::App& parent) {
    app = parent.add_subcommand("merge", "join shard outputs into one run folder");
    app->add_option("out", out, "output folder")->required();
    app->add_option("runs", inputs, "run folders to join");
    app->add_option("--plan", plan,
                    "plan.json of canopy-bench slurm: join its shards, each of which must be a "
                    "finished run of its shard");
  }

  int run() const {
    if (plan.empty() == inputs.empty())
      throwInputError("merge: name the run folders to join, or --plan (not both)");
    if (!plan.empty()) {
      mergeRuns(completeShardFolders(plan), out);
    } else {
      mergeRuns({inputs.begin(), inputs.end()}, out);
    }
    return kExitOk;
  }
};

// slurm: the experiment as a Slurm job array of shards and a merge job after it.
struct SlurmCommand {
  CLI::App* app = nullptr;
  SlurmOptions options;
  std::string config, out;

  void add(CLI::App& parent) {
    app = parent.add_subcommand(
        "slurm", "write (and with --submit, submit) a Slurm job array of shards and a merge job");
    app->add_option("--config", config, "experiment config (JSON)")->required();
    app->add_option("--shards", options.shards, "array tasks, one shard of the plan each")
        ->required();
    app->add_option("--out", out, "run folder: plan, scripts, logs, shards/ and the merged run")
        ->required();
    app->add_option("--partition", options.partition,
                    "sbatch --partition (default: the cluster's)");
    app->add_option("--time", options.time, "wall-clock limit of each task (default 02:00:00)");
    app->add_option("--cpus-per-task", options.cpusPerTask, "CPUs per task (default 2)");
    app->add_option("--gpus-per-task", options.gpusPerTask,
                    "GPUs per task (default 0; needs --gl egl)");
    app->add_option("--gl", options.gl, "backend of the tasks: osmesa (default) or egl");
    app->add_option("--account", options.account, "sbatch --account (default: the user's)");
    app->add_flag("--submit", options.submit, "submit both jobs with sbatch and print their ids");
  }

  int run() {
    options.config = config;
    options.out = out;
    std::error_code error;
    options.benchExecutable = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error) throwInputError("slurm: cannot tell where canopy-bench is ({})", error.message());
    runSlurmCommand(options);
    return kExitOk;
  }
};

}  // namespace
}  // namespace canopy

int main(int argc, char** argv) {
  using namespace canopy;
  CLI::App app{"canopy-bench: compare tree impostor methods against the polygonal reference"};
  RunCommand run;
  ExportTreeCommand exportTree;
  ExportCapturesCommand exportCaptures;
  ReportCommand report;
  MergeCommand merge;
  SlurmCommand slurm;
  RenderCommand render;
  run.add(app);
  exportTree.add(app);
  exportCaptures.add(app);
  report.add(app);
  merge.add(app);
  slurm.add(app);
  render.add(app);
  if (const auto exitCode = parseCommandLine(app, "canopy-bench", argc, argv)) return *exitCode;
  return runWithExitCodes("canopy-bench", [&]() -> int {
    if (run.quiet) {
      spdlog::set_level(spdlog::level::warn);
      ProgressBar::setEnabled(false);
    }
    if (run.listMethods) return listMethods(run.markdown);
    if (*exportTree.app) return exportTree.run();
    if (*exportCaptures.app) return exportCaptures.run(run.backend);
    if (*report.app) return report.run();
    if (*merge.app) return merge.run();
    if (*slurm.app) return slurm.run();
    if (*render.app) return render.run(run.backend);
    return run.run();
  });
}
