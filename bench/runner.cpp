#include "bench/runner.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <regex>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/report.h"
#include "bench/results_store.h"
#include "bench/run_folder.h"
#include "bench/shard_plan.h"
#include "bench/stages.h"
#include "common/atomic_file.h"
#include "common/config.h"
#include "common/file_checks.h"
#include "common/system_info.h"

namespace canopy {
namespace {

using Clock = std::chrono::steady_clock;

// Where a batch scheduler ran this process (Slurm's job, array task and node), or null.
nlohmann::json schedulerInfo() {
  const char* job = std::getenv("SLURM_JOB_ID");
  if (job == nullptr) return nullptr;
  nlohmann::json info = {{"scheduler", "slurm"}};
  for (const char* name : {"SLURM_JOB_ID", "SLURM_ARRAY_JOB_ID", "SLURM_ARRAY_TASK_ID",
                           "SLURMD_NODENAME", "SLURM_JOB_PARTITION", "SLURM_CPUS_PER_TASK"}) {
    if (const char* value = std::getenv(name)) info[name] = value;
  }
  return info;
}

// The text of --gpu-report (what nvidia-smi said on the node; the Slurm script passes it only
// when the node has nvidia-smi), at most 64 KiB.
std::string readGpuReport(const std::filesystem::path& path) {
  if (!regularFileExists(path)) throwInputError("--gpu-report: {}: no such file", path.string());
  const std::string text = readTextFile(path.string());
  return text.size() > 65536 ? text.substr(0, 65536) : text;
}

nlohmann::json runMeta(const ExperimentConfig& config, const RunOptions& options,
                       const gl::Context& context, Harness& harness) {
  return {
      {"experiment", config.name},
      {"config", config.raw},
      {"config_hash", config.hash},
      {"git_commit", gitCommit()},
      {"code_version", codeVersion()},
      {"canopy_version", CANOPY_VERSION},
      {"gl",
       {{"backend", gl::backendName(options.backend)},
        {"renderer", context.renderer()},
        {"version", context.version()},
        {"vendor", context.vendor()}}},
      {"draw_statistics", harness.statistics().source()},
      {"cpu", cpuModel()},
      {"seed", config.seed},
      {"shard", fmt::format("{}/{}", options.shardIndex, options.shardCount)},
      {"scheduler", schedulerInfo()},
      {"gpu_report", options.gpuReport.empty() ? nlohmann::json(nullptr)
                                               : nlohmann::json(readGpuReport(options.gpuReport))},
      {"started", isoTimestampUtc()}};
}

// The variants of tree `t` that this shard runs (all of them without sharding).
std::vector<size_t> variantsOfShard(const ExperimentConfig& config, const ShardPlan& plan,
                                    int shard, size_t t) {
  std::vector<size_t> mine;
  for (size_t v = 0; v < config.variants.size(); ++v) {
    if (plan.runs(shard, t, v)) mine.push_back(v);
  }
  return mine;
}

// Loads one tree and records it once (kind:"tree").
TreeSession openTree(RunContext& run, const TreeSpec& spec) {
  const std::string label = spec.label();
  const auto start = Clock::now();
  Tree tree = loadTree(spec);
  const double loadSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  spdlog::info("tree {}: {} leaves, {} wood triangles, loaded in {:.2f} s", label,
               tree.leaves.size(), tree.wood.triangleCount(), loadSeconds);
  const std::string key = "tree|" + label;
  if (!run.store.has(key)) {
    TreeRecord record;
    record.tree = label;
    record.source = spec.source();
    record.leaves = tree.leaves.size();
    record.woodTriangles = tree.wood.triangleCount();
    record.branchNodes = tree.branches.size();
    record.boundingRadius = tree.boundingSphereRadius();
    record.loadSeconds = loadSeconds;
    run.store.append(std::move(record), key);
  }
  TreeSession session(std::move(tree), label, run.config, run.device, run.harness);
  if (run.options.saveImages) session.setImageFolder(run.options.outDirectory / "images");
  // The reference first, so every variant is baked and allocated after it in the same order.
  session.reference();
  return session;
}

// Bakes the variant (after the budget search, if the config has one) and records the bake.
BakedMethod bakeVariant(RunContext& run, TreeSession& session, VariantRun& v, bool bakePending) {
  const MethodInfo& info = builtinMethods().find(v.variant.method);
  MethodVariant effective = v.variant;
  Absent<BudgetRecord> budget;
  if (run.config.budget && info.traits.memoryKnob &&
      !v.variant.params.contains(info.traits.memoryKnob->parameter)) {
    // A resumed run takes the value its bake record already holds.
    const Record* done = run.store.find(v.prefix + "bake");
    const BakeRecord* doneBake = done ? recordAs<BakeRecord>(*done) : nullptr;
    budget = doneBake && doneBake->budget ? *doneBake->budget
                                          : runBudget(run, session, v, *info.traits.memoryKnob);
    effective.params[info.traits.memoryKnob->parameter] = budget->value;
  }
  spdlog::info("{} on {}: baking", v.variant.label, session.label());
  // The asset (and its disk_bytes) matters only for the bake record; a resumed run that already
  // has it re-bakes to render, but does not write the asset again.
  std::optional<std::filesystem::path> asset;
  if (run.options.saveAssets && bakePending) {
    asset =
        run.options.outDirectory / "assets" / safeName(session.label()) / safeName(v.variant.label);
  }
  BakedMethod baked =
      bakeMethod(effective, session.tree(), run.device, session.bakeContext(), asset);
  v.params = baked.record.params;
  spdlog::info("{} on {}: bake {:.2f} s, {:.2f} MB on the GPU", v.variant.label, session.label(),
               baked.record.bakeSeconds, double(baked.record.memory.total) / 1e6);
  if (bakePending) {
    BakeRecord record = baked.record;
    record.tree = session.label();
    record.glRenderer = run.renderer;
    record.budget = budget;
    run.store.append(std::move(record), v.prefix + "bake");
  }
  return baked;
}

// A variant kept baked after its views and popping, until the tree's forests are timed.
struct BakedVariant {
  VariantRun run;
  BakedMethod baked;
  std::vector<int> forests;  // sizes still to time
};

// Bakes the variant, renders its views and popping paths; a variant with forests still to time
// is kept in `kept` for the tree's forest timing.
void runVariant(RunContext& run, TreeSession& session, const MethodVariant& variant,
                std::deque<BakedVariant>& kept) {
  VariantRun v{variant, session.label(), session.label() + "|" + variant.label + "|",
               nlohmann::json::object()};
  if (!session.hasMesh() && builtinMethods().find(variant.method).traits.needsMesh) {
    if (!run.store.has(v.prefix + "skip")) {
      SkipRecord record = v.record<SkipRecord>();
      record.reason = "needs a mesh; the tree is a capture folder (images only)";
      run.store.append(std::move(record), v.prefix + "skip");
    }
    spdlog::info("{} on {}: skipped (needs a mesh; the tree is a capture)", variant.label,
                 session.label());
    return;
  }
  const PendingWork pending = pendingWork(run, session, v);
  if (pending.done()) {
    spdlog::info("{} on {}: already complete, skipped", variant.label, session.label());
    return;
  }
  BakedMethod baked = bakeVariant(run, session, v, pending.bake);
  runViews(run, session, v, *baked.method, pending.views);
  runPopping(run, session, v, *baked.method, pending.popping);
  if (!pending.forests.empty()) kept.push_back({std::move(v), std::move(baked), pending.forests});
}

// Every variant of the shard on one tree: each baked, its views and popping done, then the
// forests of all of them timed together, so each variant's timing is spread over the same
// minutes as the others' (Harness::timeInterleaved).
void runTree(RunContext& run, TreeSession& session, const std::vector<size_t>& variants) {
  std::deque<BakedVariant> kept;
  for (size_t v : variants) runVariant(run, session, run.config.variants[v], kept);
  std::vector<ForestWork> work;
  work.reserve(kept.size());
  for (BakedVariant& k : kept) work.push_back({k.run, k.baked.method.get(), k.forests});
  runForests(run, session, work);
}

}  // namespace

std::pair<int, int> parseShard(const std::string& text) {
  std::smatch match;
  if (!std::regex_match(text, match, std::regex(R"((\d{1,9})/(\d{1,9}))"))) {
    throwInputError("--shard: '{}' must be I/N with 0 <= I < N (e.g. 0/4)", text);
  }
  const int index = std::stoi(match[1]), count = std::stoi(match[2]);
  if (count < 1 || index >= count) throwInputError("--shard: '{}' needs 0 <= I < N", text);
  return {index, count};
}

void runExperiment(const ExperimentConfig& config, const RunOptions& options) {
  // Shards split the units by expected cost (the plan canopy-bench slurm writes too).
  const ShardPlan plan = planShards(config, options.shardCount, "--shard");
  const RunFolder folder(options.outDirectory, {config.hash, codeVersion()}, options.resume);
  ResultsStore store(options.outDirectory);
  const auto metaPath = options.outDirectory / "meta.json";
  auto context = gl::createContext({options.backend});
  gl::Ledger ledger;
  gl::Device device(ledger);
  Harness harness(device, config.views.render);
  RunContext run{config, options, store, device, harness, context->renderer()};
  nlohmann::json meta = runMeta(config, options, *context, harness);
  // The parts before this one, so an interruption of this part keeps them too.
  meta["runs"] = folder.earlierRuns();
  writeTextAtomically(metaPath, meta.dump(2));
  spdlog::info("{}: {} tree(s) × {} method variant(s) on {} ({}), into {}", config.name,
               config.trees.size(), config.variants.size(), run.renderer,
               gl::backendName(options.backend), options.outDirectory.string());

  for (size_t t = 0; t < config.trees.size(); ++t) {
    const std::vector<size_t> mine = variantsOfShard(config, plan, options.shardIndex, t);
    if (mine.empty()) continue;
    TreeSession session = openTree(run, config.trees[t]);
    runTree(run, session, mine);
  }
  const auto rows = summarize(store.records());
  writeSummaries(options.outDirectory, store.records(), config.name, run.renderer);
  meta["finished"] = isoTimestampUtc();
  const nlohmann::json thisPart = {
      {"started", meta["started"]},       {"finished", meta["finished"]},
      {"git_commit", meta["git_commit"]}, {"code_version", meta["code_version"]},
      {"gl_renderer", run.renderer},      {"shard", meta["shard"]}};
  meta["runs"].push_back(thisPart);
  writeTextAtomically(metaPath, meta.dump(2));
  spdlog::info("{}: results in {}", config.name, options.outDirectory.string());
  if (options.printTable && !rows.empty())
    std::printf("%s", formatMainTable(rows, run.renderer).c_str());
}

}  // namespace canopy
