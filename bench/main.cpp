// canopy-bench: runs an experiment config and writes results/<name>/.
// Exit codes: 0 success, 2 bad input or config (one line on stderr), 1 internal error.
#include <cstdio>
#include <filesystem>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "bench/capture_export.h"
#include "bench/experiment.h"
#include "bench/merge.h"
#include "bench/report.h"
#include "bench/results_store.h"
#include "bench/runner.h"
#include "common/config.h"
#include "common/error.h"
#include "common/progress.h"
#include "common/tree_export.h"
#include "common/tree_source.h"
#include "methods/method.h"

int main(int argc, char** argv) {
  using namespace canopy;
  CLI::App app{"canopy-bench: compare tree impostor methods against the polygonal reference"};
  std::string configPath, outDirectory, backend = "osmesa", shard = "0/1";
  bool quiet = false, listMethods = false, noImages = false, fresh = false, resumeOrFresh = false;
  app.add_option("--config", configPath, "experiment config (JSON)");
  app.add_option("--out", outDirectory, "output folder (default: results/<config name>)");
  app.add_option("--gl", backend, "OpenGL backend: osmesa | egl | glfw");
  app.add_option("--shard", shard, "run slice I of N of the (tree × method) units, as I/N");
  app.add_flag("--quiet", quiet, "no progress bars and no info logs");
  app.add_flag("--no-images", noImages, "do not write rendered views as PNG");
  app.add_flag("--fresh", fresh, "move an earlier run in the output folder aside and start anew");
  app.add_flag(
      "--resume-or-fresh", resumeOrFresh,
      "resume an unfinished run of the same config and code, else start anew (make bench)");
  app.add_flag("--list-methods", listMethods, "print the registered methods and exit");
  // canopy-bench export-tree --preset broadleaf --seed 1 [--leaves N] --out DIR
  CLI::App* exportTree =
      app.add_subcommand("export-tree", "write a built-in tree as OBJ + MTL + PNG");
  std::string exportPreset = "broadleaf", exportOut;
  int64_t exportSeed = 1;
  int exportLeaves = 0;
  exportTree->add_option("--preset", exportPreset, "broadleaf | shrub | sparse");
  exportTree->add_option("--seed", exportSeed, "L-system seed");
  exportTree->add_option("--leaves", exportLeaves, "leaf count (0: the preset's)");
  exportTree->add_option("--out", exportOut, "output folder")->required();
  // canopy-bench export-captures --preset sparse --train 22 --test 8 --resolution 512 --out DIR
  CLI::App* exportCapturesCommand = app.add_subcommand(
      "export-captures", "photograph a built-in tree into a NeRF-layout capture folder");
  std::string capturePreset = "broadleaf", captureOut;
  int64_t captureSeed = 1;
  int captureLeaves = 0;
  CaptureExportOptions captureOptions;
  exportCapturesCommand->add_option("--preset", capturePreset, "broadleaf | shrub | sparse");
  exportCapturesCommand->add_option("--seed", captureSeed, "L-system seed");
  exportCapturesCommand->add_option("--leaves", captureLeaves, "leaf count (0: the preset's)");
  exportCapturesCommand->add_option("--train", captureOptions.trainViews, "training views");
  exportCapturesCommand->add_option("--test", captureOptions.testViews, "held-out test views");
  exportCapturesCommand->add_option("--resolution", captureOptions.resolution, "pixels per side");
  exportCapturesCommand->add_option("--distance", captureOptions.distance,
                                    "camera distance in bounding radii");
  exportCapturesCommand->add_option("--out", captureOut, "output folder")->required();
  // canopy-bench report RUN... : rewrites summaries (md, csv, tex, popping.csv) from metrics.jsonl
  CLI::App* report =
      app.add_subcommand("report", "rewrite a run's summaries from its metrics.jsonl");
  std::vector<std::string> reportRuns;
  report->add_option("runs", reportRuns, "run folders")->required();
  // canopy-bench merge OUT RUN... : joins shard outputs
  CLI::App* merge = app.add_subcommand("merge", "join shard outputs into one run folder");
  std::string mergeOut;
  std::vector<std::string> mergeInputs;
  merge->add_option("out", mergeOut, "output folder")->required();
  merge->add_option("runs", mergeInputs, "run folders to join")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  return runWithExitCodes("canopy-bench", [&]() -> int {
    if (listMethods) {
      for (const std::string& name : builtinMethods().names()) std::printf("%s\n", name.c_str());
      return kExitOk;
    }
    if (*exportTree) {
      TreeSpec spec;
      spec.preset = exportPreset;
      if (exportSeed < 0) throwInputError("--seed: must be >= 0");
      spec.seed = static_cast<uint64_t>(exportSeed);
      spec.leaves = exportLeaves;
      if (exportLeaves < 0) throwInputError("--leaves: must be >= 0");
      const Tree tree = loadTree(spec);
      std::printf("%s\n", exportTreeObj(tree, exportOut).string().c_str());
      return kExitOk;
    }
    if (*exportCapturesCommand) {
      if (captureSeed < 0 || captureLeaves < 0) throwInputError("--seed, --leaves: must be >= 0");
      if (captureOptions.trainViews < 2 || captureOptions.testViews < 1 ||
          captureOptions.resolution < 16 || captureOptions.resolution > 4096 ||
          !(captureOptions.distance > 1.1f)) {
        throwInputError(
            "export-captures: need --train >= 2, --test >= 1, --resolution in [16, 4096], "
            "--distance > 1.1");
      }
      TreeSpec spec;
      spec.preset = capturePreset;
      spec.seed = static_cast<uint64_t>(captureSeed);
      spec.leaves = captureLeaves;
      exportCaptures(loadTree(spec), captureOut, captureOptions, gl::parseBackend(backend));
      std::printf("%s\n", captureOut.c_str());
      return kExitOk;
    }
    if (*report) {
      for (const std::string& run : reportRuns) {
        const std::filesystem::path folder(run);
        if (!std::filesystem::exists(folder / "metrics.jsonl"))
          throwInputError("{}: no metrics.jsonl (not a run folder)", run);
        const nlohmann::json meta = readJsonFile((folder / "meta.json").string());
        writeSummaries(folder, ResultsStore::readRecords(folder / "metrics.jsonl"),
                       meta.value("experiment", folder.filename().string()),
                       meta.value("gl", nlohmann::json::object()).value("renderer", "unknown"));
        std::printf("%s\n", run.c_str());
      }
      return kExitOk;
    }
    if (*merge) {
      if (quiet) spdlog::set_level(spdlog::level::warn);
      std::vector<std::filesystem::path> inputs(mergeInputs.begin(), mergeInputs.end());
      mergeRuns(inputs, mergeOut);
      return kExitOk;
    }
    if (configPath.empty())
      throwInputError("--config: required (e.g. --config configs/default.json)");
    if (quiet) {
      spdlog::set_level(spdlog::level::warn);
      ProgressBar::setEnabled(false);
    }
    const ExperimentConfig config = readExperimentConfig(configPath);
    RunOptions options;
    options.backend = gl::parseBackend(backend);
    std::tie(options.shardIndex, options.shardCount) = parseShard(shard);
    options.outDirectory = outDirectory.empty() ? std::filesystem::path("results") / config.name
                                                : std::filesystem::path(outDirectory);
    options.saveImages = !noImages;
    if (fresh && resumeOrFresh) throwInputError("--fresh and --resume-or-fresh exclude each other");
    options.resume = fresh           ? ResumePolicy::kFresh
                     : resumeOrFresh ? ResumePolicy::kResumeOrFresh
                                     : ResumePolicy::kResume;
    options.printTable = !quiet;
    runExperiment(config, options);
    return kExitOk;
  });
}
