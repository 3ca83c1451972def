#include "bench/runner.h"

#include <chrono>
#include <fstream>
#include <map>
#include <optional>
#include <regex>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/harness.h"
#include "bench/report.h"
#include "bench/results_store.h"
#include "common/atomic_file.h"
#include "common/captures.h"
#include "common/image.h"
#include "common/metrics.h"
#include "common/progress.h"
#include "common/system_info.h"

namespace canopy {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string safeName(const std::string& label) {
  return std::regex_replace(label, std::regex("[^A-Za-z0-9_.=,-]"), "_");
}

std::string viewKey(const ViewPose& pose) {
  return fmt::format("d{:g}_e{:g}_a{:g}", pose.distance, pose.elevation, pose.azimuth);
}

// A view every method of a tree is scored on: an orbit pose around a mesh tree, or a held-out
// test view of a capture (whose reference is the photograph itself).
struct EvalView {
  std::string key;
  Camera camera;
  int width = 0, height = 0;
  nlohmann::json fields;                 // distance/elevation/azimuth or capture view name
  const ImageRgbaF* captured = nullptr;  // the reference of a capture view
};

std::vector<EvalView> evaluationViews(const Tree& tree, const ExperimentConfig& config) {
  std::vector<EvalView> views;
  const RenderSettings& render = config.views.render;
  if (tree.captures) {
    const float radius = tree.boundingSphereRadius();
    for (const CapturedView& v : tree.captures->test) {
      const std::string stem = std::filesystem::path(v.name).stem().string();
      const double distance =
          std::round(10.0 * glm::length(v.camera.position - tree.bounds.center()) / radius) / 10.0;
      views.push_back({"test_" + stem,
                       v.camera,
                       v.image.width,
                       v.image.height,
                       {{"capture_view", v.name}, {"distance", distance}},
                       &v.image});
    }
    return views;
  }
  for (const ViewPose& pose :
       makeViewRings(config.views.distances, config.views.elevations, config.views.azimuths)) {
    views.push_back(
        {viewKey(pose),
         orbitCamera(tree.bounds, pose, render.fovYDegrees),
         render.width,
         render.height,
         {{"distance", pose.distance}, {"elevation", pose.elevation}, {"azimuth", pose.azimuth}},
         nullptr});
  }
  return views;
}

struct BakedMethod {
  std::unique_ptr<Method> method;
  nlohmann::json record;  // the kind:"bake" record
};

// Bakes and uploads one method under its own ledger owner and measures what the record needs.
BakedMethod bakeMethod(const MethodVariant& variant, const Tree& tree, gl::Device& device,
                       uint64_t seed, const std::filesystem::path& assetFolder, bool saveAsset,
                       const std::function<ImageRgbaF(const Camera&, int, int)>& photograph) {
  BakedMethod baked;
  baked.method =
      builtinMethods().find(variant.method).create(variant.params, "methods." + variant.label);
  const bool peakReset = resetPeakRss();
  BakeContext context;
  context.seed = seed;
  context.photograph = photograph;
  const auto start = Clock::now();
  baked.method->bake(tree, context);
  const double bakeSeconds = secondsSince(start);
  const uint64_t peak = peakRssBytes();
  {
    gl::Device::OwnerScope owner(device, variant.label);
    baked.method->upload(device);
  }
  gl::checkError(("upload of " + variant.label).c_str());
  uint64_t diskBytes = 0;
  if (saveAsset) {
    std::filesystem::remove_all(assetFolder);
    std::filesystem::create_directories(assetFolder);
    AssetFolder asset(assetFolder);
    baked.method->save(asset);
    diskBytes = asset.sizeOnDisk();
  }
  baked.record = {{"kind", "bake"},
                  {"bake_s", bakeSeconds},
                  {"bake_peak_rss_bytes", peak},
                  {"bake_peak_rss_scope", peakReset ? "bake" : "process"},
                  {"memory_bytes", gl::toJson(device.ledger().totals(variant.label))},
                  {"disk_bytes", saveAsset ? nlohmann::json(diskBytes) : nlohmann::json()},
                  {"params", baked.method->effectiveParams()},
                  {"report", baked.method->bakeReport()}};
  return baked;
}

using Photographer = std::function<ImageRgbaF(const Camera&, int, int)>;

nlohmann::json knobValue(const MemoryKnob& knob, double value) {
  return knob.integer ? nlohmann::json(int64_t(std::llround(value))) : nlohmann::json(value);
}

// The budget's search for one variant: each trial bakes and uploads the method with the knob at
// a value (under its own ledger owner, released after), and measures its memory or mean PSNR.
nlohmann::json searchBudget(const BudgetSettings& budget, const MemoryKnob& knob,
                            const MethodVariant& variant, const Tree& tree, gl::Device& device,
                            uint64_t seed, const Photographer& photograph,
                            const std::function<double(Method&)>& meanPsnr) {
  std::map<double, double> memoryAt;
  const auto trial = [&](double value) {
    MethodVariant v = variant;
    v.params[knob.parameter] = knobValue(knob, value);
    v.label += "/budget";
    BakedMethod baked = bakeMethod(v, tree, device, seed, {}, false, photograph);
    memoryAt[value] = baked.record["memory_bytes"]["total"].get<double>() / 1e6;
    return baked;
  };
  KnobSearch search;
  if (budget.memoryMb > 0.0) {
    search = bisectToTarget(
        knob, budget.memoryMb, budget.tolerance,
        [&](double value) {
          trial(value);
          spdlog::info("{}: budget {} = {:g} → {:.2f} MB", variant.label, knob.parameter, value,
                       memoryAt[value]);
          return memoryAt[value];
        },
        budget.maxSteps);
  } else {
    search = leastMemoryReaching(
        knob, budget.psnrDb,
        [&](double value) {
          BakedMethod baked = trial(value);
          const double psnr = meanPsnr(*baked.method);
          spdlog::info("{}: budget {} = {:g} → {:.2f} MB, {:.2f} dB", variant.label, knob.parameter,
                       value, memoryAt[value], psnr);
          return psnr;
        },
        budget.maxSteps);
  }
  nlohmann::json trace = nlohmann::json::array();
  for (const auto& [value, measured] : search.trace)
    trace.push_back({{"value", knobValue(knob, value)},
                     {"measured", measured},
                     {"memory_mb", memoryAt[value]}});
  return {{"mode", budget.memoryMb > 0.0 ? "memory_mb" : "psnr_db"},
          {"target", budget.memoryMb > 0.0 ? budget.memoryMb : budget.psnrDb},
          {"tolerance", budget.tolerance},
          {"parameter", knob.parameter},
          {"value", knobValue(knob, search.value)},
          {"measured", search.measured},
          {"memory_mb", memoryAt[search.value]},
          {"reached", search.reached},
          {"steps", search.steps},
          {"trace", trace}};
}

nlohmann::json readPreviousRuns(const std::filesystem::path& metaPath) {
  if (!std::filesystem::exists(metaPath)) return nlohmann::json::array();
  try {
    const nlohmann::json meta = nlohmann::json::parse(std::ifstream(metaPath));
    return meta.value("runs", nlohmann::json::array());
  } catch (const std::exception&) {
    return nlohmann::json::array();
  }
}

}  // namespace

std::pair<int, int> parseShard(const std::string& text) {
  std::smatch match;
  if (!std::regex_match(text, match, std::regex(R"((\d+)/(\d+))"))) {
    throwInputError("--shard: '{}' must be I/N (e.g. 0/4)", text);
  }
  const int index = std::stoi(match[1]), count = std::stoi(match[2]);
  if (count < 1 || index >= count) throwInputError("--shard: '{}' needs 0 <= I < N", text);
  return {index, count};
}

void runExperiment(const ExperimentConfig& config, const RunOptions& options) {
  ResultsStore store(options.outDirectory);
  const auto metaPath = options.outDirectory / "meta.json";
  auto context = gl::createContext({options.backend});
  const std::string renderer = context->renderer();
  nlohmann::json meta = {{"experiment", config.name},
                         {"config", config.raw},
                         {"config_hash", config.hash},
                         {"git_commit", gitCommit()},
                         {"canopy_version", CANOPY_VERSION},
                         {"gl",
                          {{"backend", gl::backendName(options.backend)},
                           {"renderer", renderer},
                           {"version", context->version()},
                           {"vendor", context->vendor()}}},
                         {"cpu", cpuModel()},
                         {"seed", config.seed},
                         {"shard", fmt::format("{}/{}", options.shardIndex, options.shardCount)},
                         {"started", isoTimestampUtc()}};
  nlohmann::json runs = readPreviousRuns(metaPath);
  writeTextAtomically(metaPath, nlohmann::json(meta).dump(2));
  spdlog::info("{}: {} tree(s) × {} method variant(s) on {} ({})", config.name, config.trees.size(),
               config.variants.size(), renderer, gl::backendName(options.backend));

  gl::Ledger ledger;
  gl::Device device(ledger);
  Harness harness(device, config.views.render);
  const MethodVariant referenceVariant{"polygonal", nlohmann::json::object(), "polygonal"};

  for (size_t t = 0; t < config.trees.size(); ++t) {
    const TreeSpec& spec = config.trees[t];
    std::vector<size_t> mine;
    for (size_t v = 0; v < config.variants.size(); ++v) {
      if ((t * config.variants.size() + v) % size_t(options.shardCount) ==
          size_t(options.shardIndex))
        mine.push_back(v);
    }
    if (mine.empty()) continue;
    const std::string treeLabel = spec.label();
    const auto loadStart = Clock::now();
    const Tree tree = loadTree(spec);
    const double loadSeconds = secondsSince(loadStart);
    spdlog::info("tree {}: {} leaves, {} wood triangles, loaded in {:.2f} s", treeLabel,
                 tree.leaves.size(), tree.wood.triangleCount(), loadSeconds);
    const std::string treeKey = "tree|" + treeLabel;
    if (!store.has(treeKey)) {
      store.append({{"kind", "tree"},
                    {"tree", treeLabel},
                    {"source", spec.source()},
                    {"leaves", tree.leaves.size()},
                    {"wood_triangles", tree.wood.triangleCount()},
                    {"branch_nodes", tree.branches.size()},
                    {"bounding_radius", tree.boundingSphereRadius()},
                    {"load_s", loadSeconds}},
                   treeKey);
    }
    const auto forest = [&](int size) {
      return layoutForest(size, tree.boundingSphereRadius(), config.seed);
    };

    // The reference, baked once per tree; its images and forest times are made on first need.
    std::optional<BakedMethod> reference;
    std::map<std::string, ImageRgba8> referenceImages;
    std::map<int, FrameTimes> referenceTimes;
    std::map<std::string, std::vector<ImageRgba8>> referencePaths;  // popping frames per path
    const auto ensureReference = [&] {
      if (!reference)
        reference = bakeMethod(referenceVariant, tree, device, config.seed, {}, false, {});
    };
    harness.setTreeBounds(tree.bounds);
    const std::vector<EvalView> views = evaluationViews(tree, config);
    const auto referenceImage = [&](const EvalView& view) -> const ImageRgba8& {
      auto [it, inserted] = referenceImages.try_emplace(view.key);
      if (inserted) {
        if (view.captured) {
          it->second = harness.display(*view.captured);
        } else {
          ensureReference();
          it->second = harness.display(
              harness.renderLinearAt(*reference->method, view.camera, view.width, view.height));
        }
        if (options.saveImages) {
          writePng(options.outDirectory / "images" / safeName(treeLabel) / "reference" /
                       (view.key + ".png"),
                   withOpaqueAlpha(it->second));
        }
      }
      return it->second;
    };
    // Image-based methods photograph a mesh tree through the reference, as a camera would.
    const auto photograph = [&](const Camera& camera, int width, int height) {
      ensureReference();
      return harness.renderLinearAt(*reference->method, camera, width, height);
    };
    const auto referenceTime = [&](int size) -> const FrameTimes* {
      if (tree.captures) return nullptr;  // no mesh: nothing to time against
      ensureReference();
      auto [it, inserted] = referenceTimes.try_emplace(size);
      if (inserted) {
        it->second =
            harness.timeForest(*reference->method, forest(size), tree.bounds, config.forests.frames,
                               config.forests.warmup, config.forests.width, config.forests.height,
                               config.forests.cameraPath);
      }
      return &it->second;
    };

    for (size_t v : mine) {
      const MethodVariant& variant = config.variants[v];
      const std::string prefix = treeLabel + "|" + variant.label + "|";
      const nlohmann::json common = {
          {"tree", treeLabel}, {"method", variant.method}, {"variant", variant.label}};
      const MethodInfo& info = builtinMethods().find(variant.method);
      if (tree.captures && info.traits.needsMesh) {
        if (!store.has(prefix + "skip")) {
          nlohmann::json record = common;
          record.update({{"kind", "skip"},
                         {"reason", "needs a mesh; the tree is a capture folder (images only)"}});
          store.append(record, prefix + "skip");
        }
        spdlog::info("{} on {}: skipped (needs a mesh; the tree is a capture)", variant.label,
                     treeLabel);
        continue;
      }
      std::vector<const EvalView*> pendingViews;
      for (const EvalView& view : views)
        if (!store.has(prefix + "view|" + view.key)) pendingViews.push_back(&view);
      std::vector<int> pendingForests;
      for (int size : config.forests.sizes)
        if (!store.has(prefix + fmt::format("forest|{}", size))) pendingForests.push_back(size);
      std::vector<std::string> pendingPaths;
      if (config.popping.enabled)
        for (const char* path : {"dolly", "orbit"})
          if (!store.has(prefix + "popping|" + path)) pendingPaths.push_back(path);
      const bool bakeDone = store.has(prefix + "bake");
      if (bakeDone && pendingViews.empty() && pendingForests.empty() && pendingPaths.empty()) {
        spdlog::info("{} on {}: already complete, skipped", variant.label, treeLabel);
        continue;
      }
      // Equal-memory (or PSNR-target) comparisons turn the method's memory knob first; a resumed
      // run takes the value its bake record already holds.
      MethodVariant effective = variant;
      nlohmann::json budgetRecord;
      if (config.budget && info.traits.memoryKnob &&
          !variant.params.contains(info.traits.memoryKnob->parameter)) {
        const MemoryKnob& knob = *info.traits.memoryKnob;
        const nlohmann::json* done = store.find(prefix + "bake");
        if (done && done->contains("budget")) {
          budgetRecord = (*done)["budget"];
        } else {
          spdlog::info("{} on {}: searching {} for the budget", variant.label, treeLabel,
                       knob.parameter);
          budgetRecord = searchBudget(
              *config.budget, knob, variant, tree, device, config.seed, photograph,
              [&](Method& method) {
                double sum = 0.0;
                for (const EvalView& view : views) {
                  sum += compareImages(referenceImage(view),
                                       harness.display(harness.renderLinearAt(
                                           method, view.camera, view.width, view.height)))
                             .psnr;
                }
                return views.empty() ? 0.0 : sum / double(views.size());
              });
        }
        effective.params[knob.parameter] = budgetRecord["value"];
      }
      spdlog::info("{} on {}: baking", variant.label, treeLabel);
      BakedMethod baked = bakeMethod(
          effective, tree, device, config.seed,
          options.outDirectory / "assets" / safeName(treeLabel) / safeName(variant.label),
          // The asset (and its disk_bytes) matters only for the bake record; a resumed run that
          // already has it re-bakes to render, but does not write the asset again.
          options.saveAssets && !bakeDone, photograph);
      const nlohmann::json params = baked.record["params"];
      spdlog::info("{} on {}: bake {:.2f} s, {:.2f} MB on the GPU", variant.label, treeLabel,
                   baked.record["bake_s"].get<double>(),
                   baked.record["memory_bytes"]["total"].get<double>() / 1e6);
      if (!bakeDone) {
        nlohmann::json record = common;
        record.update(baked.record);
        record["gl_renderer"] = renderer;
        if (!budgetRecord.is_null()) record["budget"] = budgetRecord;
        store.append(record, prefix + "bake");
      }
      {
        ProgressBar progress(fmt::format("{} {} views", treeLabel, variant.label),
                             pendingViews.size());
        for (const EvalView* view : pendingViews) {
          const ImageRgba8& expected = referenceImage(*view);
          const ImageRgba8 image = harness.display(
              harness.renderLinearAt(*baked.method, view->camera, view->width, view->height));
          const ImageMetrics metrics = compareImages(expected, image);
          if (options.saveImages) {
            writePng(options.outDirectory / "images" / safeName(treeLabel) /
                         safeName(variant.label) / (view->key + ".png"),
                     withOpaqueAlpha(image));
          }
          nlohmann::json record = common;
          record.update(view->fields);
          record.update(
              {{"kind", "view"},
               {"params", params},
               {"psnr", metrics.psnr},
               {"psnr_frame", metrics.psnrFrame},
               {"ssim", metrics.ssim},
               {"coverage_error", metrics.coverageError},
               {"union_pixels", metrics.unionPixels},
               {"shading", config.views.render.shading == Shading::kLit ? "lit" : "unlit"},
               {"shadows", config.views.render.shadows}});
          store.append(record, prefix + "view|" + view->key);
          progress.advance();
        }
      }
      {
        ProgressBar progress(fmt::format("{} {} forests", treeLabel, variant.label),
                             pendingForests.size());
        for (int size : pendingForests) {
          // Reference first, then the method, back to back in this process: the ratio is from one
          // run.
          const bool isReference = variant.method == "polygonal" && variant.params.empty();
          const FrameTimes* polygonal = referenceTime(size);
          const FrameTimes times =
              isReference ? *polygonal
                          : harness.timeForest(*baked.method, forest(size), tree.bounds,
                                               config.forests.frames, config.forests.warmup,
                                               config.forests.width, config.forests.height,
                                               config.forests.cameraPath);
          nlohmann::json record = common;
          record.update({{"kind", "forest"},
                         {"params", params},
                         {"trees", size},
                         {"frames", times.frames},
                         {"warmup", config.forests.warmup},
                         {"resolution", {config.forests.width, config.forests.height}},
                         {"frame_ms_median", times.medianMs},
                         {"frame_ms_p95", times.p95Ms},
                         {"frame_ms_mean", times.meanMs},
                         {"fps", 1000.0 / times.medianMs},
                         {"polygonal_frame_ms_median",
                          polygonal ? nlohmann::json(polygonal->medianMs) : nlohmann::json()},
                         {"speedup_vs_polygonal",
                          polygonal ? nlohmann::json(polygonal->medianMs / times.medianMs)
                                    : nlohmann::json()},
                         {"gl_renderer", renderer}});
          store.append(record, prefix + fmt::format("forest|{}", size));
          progress.advance();
        }
      }
      // Popping: a dolly from close to far and an orbit, frame by frame against the reference.
      for (const std::string& pathName :
           tree.captures ? std::vector<std::string>{} : pendingPaths) {
        const PoppingSettings& popping = config.popping;
        const float fov = config.views.render.fovYDegrees;
        const std::vector<PathFrame> path = pathName == "dolly"
                                                ? dollyPath(tree.bounds, popping, fov)
                                                : orbitPath(tree.bounds, popping, fov);
        auto [cached, inserted] = referencePaths.try_emplace(pathName);
        if (inserted) {
          ensureReference();
          std::vector<uint64_t> ignored;
          cached->second =
              renderPath(harness, *reference->method, path, popping.width, popping.height, ignored);
        }
        std::vector<uint64_t> signatures;
        const std::vector<ImageRgba8> frames =
            renderPath(harness, *baked.method, path, popping.width, popping.height, signatures);
        const TemporalMetrics metrics = temporalMetrics(frames, cached->second, signatures);
        std::vector<float> distances;
        for (const PathFrame& frame : path) distances.push_back(frame.distance);
        nlohmann::json record = common;
        record.update({{"kind", "popping"},
                       {"params", params},
                       {"path", pathName},
                       {"resolution", {popping.width, popping.height}},
                       {"distance", distances},
                       {"psnr_frame", metrics.psnr},
                       {"change", metrics.change},
                       {"reference_change", metrics.referenceChange},
                       {"temporal_excess", metrics.excess},
                       {"lod_switch", metrics.lodSwitch},
                       {"peak_excess", metrics.peakExcess},
                       {"mean_excess", metrics.meanExcess},
                       {"switches", metrics.switches}});
        store.append(record, prefix + "popping|" + pathName);
        spdlog::info(
            "{} on {}: popping along the {}: peak {:.2f}, mean {:.2f} (8-bit RMS), {} LoD "
            "switches",
            variant.label, treeLabel, pathName, metrics.peakExcess, metrics.meanExcess,
            metrics.switches);
      }
    }
  }
  writeSummaries(options.outDirectory, store.records(), config.name, renderer);
  meta["finished"] = isoTimestampUtc();
  runs.push_back({{"started", meta["started"]},
                  {"finished", meta["finished"]},
                  {"git_commit", meta["git_commit"]},
                  {"gl_renderer", renderer},
                  {"shard", meta["shard"]}});
  meta["runs"] = runs;
  writeTextAtomically(metaPath, meta.dump(2));
  spdlog::info("{}: results in {}", config.name, options.outDirectory.string());
}

}  // namespace canopy
