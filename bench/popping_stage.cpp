// The popping stage: a dolly from close to far and an orbit, every frame scored against the
// reference's and the method's frame-to-frame change compared with the reference's.
#include <spdlog/spdlog.h>

#include "bench/popping.h"
#include "bench/stages.h"

namespace canopy {

void runPopping(RunContext& run, TreeSession& session, const VariantRun& v, Method& method,
                const std::vector<std::string>& paths) {
  const PoppingSettings& popping = run.config.popping;
  const float fov = run.config.views.render.fovYDegrees;
  for (const std::string& pathName : paths) {
    const std::vector<PathFrame> path = pathName == "dolly"
                                            ? dollyPath(session.tree().bounds, popping, fov)
                                            : orbitPath(session.tree().bounds, popping, fov);
    const std::vector<ImageRgba8>& reference =
        session.referencePath(pathName, path, popping.width, popping.height);
    std::vector<uint64_t> signatures;
    const std::vector<ImageRgba8> frames =
        renderPath(run.harness, method, path, popping.width, popping.height, signatures);
    const TemporalMetrics metrics = temporalMetrics(frames, reference, signatures);
    PoppingRecord record = v.record<PoppingRecord>();
    record.path = pathName;
    record.resolution = {popping.width, popping.height};
    for (const PathFrame& frame : path) record.distance.push_back(frame.distance);
    record.psnrFrame = metrics.psnr;
    record.change = metrics.change;
    record.referenceChange = metrics.referenceChange;
    record.temporalExcess = metrics.excess;
    record.lodSwitch = metrics.lodSwitch;
    record.peakExcess = metrics.peakExcess;
    record.meanExcess = metrics.meanExcess;
    record.switches = metrics.switches;
    run.store.append(std::move(record), v.prefix + "popping|" + pathName);
    spdlog::info(
        "{} on {}: popping along the {}: peak {:.2f}, mean {:.2f} (8-bit RMS), {} LoD switches",
        v.variant.label, session.label(), pathName, metrics.peakExcess, metrics.meanExcess,
        metrics.switches);
  }
}

}  // namespace canopy
