// The forests stage: each pending forest size timed interleaved with the reference on the same
// camera path (Harness::timeInterleaved) and its frames scored against the reference's.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/stages.h"
#include "common/progress.h"

namespace canopy {
namespace {

nlohmann::json numberOrNull(bool present, double value) {
  return present ? nlohmann::json(value) : nlohmann::json();
}

}  // namespace

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
    nlohmann::json record = v.common;
    record.update(
        {{"kind", "forest"},
         {"params", v.params},
         {"trees", size},
         {"frames", times.method.frames},
         {"warmup", timing.warmup},
         {"blocks", times.blockRatios.size()},
         {"resolution", {timing.width, timing.height}},
         {"frame_ms_median", times.method.medianMs},
         {"frame_ms_p95", times.method.p95Ms},
         {"frame_ms_mean", times.method.meanMs},
         {"fps", 1000.0 / times.method.medianMs},
         {"polygonal_frame_ms_median", numberOrNull(compared, times.reference.medianMs)},
         {"speedup_vs_polygonal", numberOrNull(compared, times.speedupMedian)},
         {"speedup_spread",
          compared ? nlohmann::json({times.speedupQ25, times.speedupQ75}) : nlohmann::json()},
         {"block_speedups", compared ? nlohmann::json(times.blockRatios) : nlohmann::json()},
         {"psnr", numberOrNull(compared, times.psnr)},
         {"flip", numberOrNull(compared, times.flip)},
         {"coverage_error", numberOrNull(compared, times.coverageError)},
         {"reference_coverage", numberOrNull(compared, times.referenceCoverage)},
         {"drawn", drawnJson(times.drawn)},
         {"gl_renderer", run.renderer}});
    run.store.append(record, v.prefix + fmt::format("forest|{}", size));
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
