// The forests stage: each pending forest size timed interleaved with the reference on the same
// camera path, every variant of the tree in one timing (Harness::timeInterleaved), and each
// variant's frames scored against the reference's.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/stages.h"
#include "common/progress.h"

namespace canopy {
namespace {

ForestRecord forestRecord(const RunContext& run, const VariantRun& v, int size,
                          const InterleavedTimes& times, bool compared) {
  const ForestTiming timing = run.config.forests.timingFor(size);
  const double nan = std::nan("");
  ForestRecord record = v.record<ForestRecord>();
  record.trees = size;
  record.frames = times.method.frames;
  record.warmup = timing.warmup;
  record.blocks = static_cast<int>(times.blockRatios.size());
  record.repeats = times.repeats;
  record.resolution = {timing.width, timing.height};
  record.frameMsMedian = times.method.medianMs;
  record.frameMsP95 = times.method.p95Ms;
  record.frameMsMean = times.method.meanMs;
  record.fps = 1000.0 / times.method.medianMs;
  record.polygonalFrameMsMedian = compared ? times.reference.medianMs : nan;
  record.speedupVsPolygonal = compared ? times.speedup : nan;
  if (compared) {
    record.speedupSpread = std::array<double, 2>{times.speedupQ25, times.speedupQ75};
    record.blockSpeedups = times.blockRatios;
    record.frameSpeedups = times.frameRatios;
  }
  record.psnr = compared ? times.psnr : nan;
  record.flip = compared ? times.flip : nan;
  record.coverageError = compared ? times.coverageError : nan;
  record.referenceCoverage = compared ? times.referenceCoverage : nan;
  record.drawn = drawnRecord(times.drawn);
  record.glRenderer = run.renderer;
  return record;
}

}  // namespace

void runForests(RunContext& run, TreeSession& session, std::span<const ForestWork> work) {
  std::vector<int> sizes;  // in the config's order
  for (int size : run.config.forests.sizes) {
    for (const ForestWork& w : work) {
      if (std::ranges::count(w.sizes, size) > 0) {
        sizes.push_back(size);
        break;
      }
    }
  }
  if (sizes.empty()) return;
  Method* reference = session.reference();  // null for capture trees: timed alone
  ProgressBar progress(fmt::format("{} forests ({} variants)", session.label(), work.size()),
                       sizes.size());
  for (int size : sizes) {
    std::vector<const ForestWork*> due;
    std::vector<Method*> methods;
    for (const ForestWork& w : work) {
      if (std::ranges::count(w.sizes, size) == 0) continue;
      due.push_back(&w);
      methods.push_back(w.method);
    }
    const std::vector<Instance> forest = session.forest(size);
    const ForestTiming timing = run.config.forests.timingFor(size);
    std::vector<InterleavedTimes> times;
    if (reference) {
      times = run.harness.timeInterleaved(*reference, methods, forest, session.tree().bounds,
                                          timing, &session.forestFrames(size));
      if (times.front().referenceCoverage <= 0.0) {
        throwInputError(
            "forests: the reference draws nothing in any scored frame of the {}-tree forest "
            "along the camera path; timing empty frames measures nothing (check "
            "forests.camera_path)",
            size);
      }
    } else {
      // Without a reference (a capture tree), each method is timed against itself and nothing
      // is compared: its ratio and scores are left out.
      for (Method* method : methods) {
        times.push_back(
            run.harness.timeInterleaved(*method, *method, forest, session.tree().bounds, timing));
      }
    }
    for (size_t k = 0; k < due.size(); ++k) {
      const VariantRun& v = due[k]->variant;
      const InterleavedTimes& t = times[k];
      run.store.append(forestRecord(run, v, size, t, reference != nullptr),
                       v.prefix + fmt::format("forest|{}", size));
      if (reference) {
        spdlog::info(
            "{} on {}, {} trees: {:.1f} ms ({:.2f}× polygonal, IQR {:.2f}–{:.2f}), FLIP {:.3f}",
            v.variant.label, session.label(), size, t.method.medianMs, t.speedup, t.speedupQ25,
            t.speedupQ75, t.flip);
      }
    }
    progress.advance();
  }
}

}  // namespace canopy
