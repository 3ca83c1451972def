// The forests stage: each pending forest size timed interleaved with the reference on the same
// camera path (Harness::timeInterleaved) and its frames scored against the reference's.
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/stages.h"
#include "common/progress.h"

namespace canopy {

void runForests(RunContext& run, TreeSession& session, const VariantRun& v, Method& method,
                const std::vector<int>& sizes) {
  const ForestTiming& timing = run.config.forests.timing;
  Method* reference = session.reference();  // null for capture trees: timed alone
  ProgressBar progress(fmt::format("{} {} forests", session.label(), v.variant.label),
                       sizes.size());
  for (int size : sizes) {
    const std::vector<Instance> forest = session.forest(size);
    // Without a reference (a capture tree), the method is timed against itself and nothing is
    // compared: its ratio and scores are left out.
    const InterleavedTimes times = run.harness.timeInterleaved(
        reference ? *reference : method, method, forest, session.tree().bounds, timing,
        reference ? &session.forestFrames(size) : nullptr);
    const bool compared = reference != nullptr;
    if (compared && times.referenceCoverage <= 0.0) {
      throwInputError(
          "forests: the reference draws nothing in any scored frame of the {}-tree forest along "
          "the camera path; timing empty frames measures nothing (check forests.camera_path)",
          size);
    }
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
    record.speedupVsPolygonal = compared ? times.speedupMedian : nan;
    if (compared) {
      record.speedupSpread = std::array<double, 2>{times.speedupQ25, times.speedupQ75};
      record.blockSpeedups = times.blockRatios;
    }
    record.psnr = compared ? times.psnr : nan;
    record.flip = compared ? times.flip : nan;
    record.coverageError = compared ? times.coverageError : nan;
    record.referenceCoverage = compared ? times.referenceCoverage : nan;
    record.drawn = drawnRecord(times.drawn);
    record.glRenderer = run.renderer;
    run.store.append(std::move(record), v.prefix + fmt::format("forest|{}", size));
    if (compared) {
      spdlog::info(
          "{} on {}, {} trees: {:.1f} ms ({:.2f}× polygonal, IQR {:.2f}–{:.2f}), "
          "FLIP {:.3f}",
          v.variant.label, session.label(), size, times.method.medianMs, times.speedupMedian,
          times.speedupQ25, times.speedupQ75, times.flip);
    }
    progress.advance();
  }
}

}  // namespace canopy
