// The views stage: every pending view of a variant rendered, scored against the reference and
// recorded; also what a variant still has to do (pendingWork).
#include <fmt/format.h>

#include "bench/stages.h"
#include "common/metrics.h"
#include "common/progress.h"

namespace canopy {

DrawnRecord drawnRecord(const DrawnStats& drawn) {
  DrawnRecord record{
      drawn.counts.primitives, drawn.counts.fragments, drawn.leafGeometryFraction, {}, {}, {}};
  if (!drawn.instancesPerLevel.empty()) record.instancesPerLevel = drawn.instancesPerLevel;
  if (!drawn.woodInstancesPerLevel.empty())
    record.woodInstancesPerLevel = drawn.woodInstancesPerLevel;
  record.instancesVisible = drawn.instancesVisible;
  return record;
}

PendingWork pendingWork(const RunContext& run, const TreeSession& session, const VariantRun& v) {
  PendingWork pending;
  const ResultsStore& store = run.store;
  pending.bake = !store.has(v.prefix + "bake");
  for (const EvalView& view : session.views())
    if (!store.has(v.prefix + "view|" + view.key)) pending.views.push_back(&view);
  for (int size : run.config.forests.sizes)
    if (!store.has(v.prefix + fmt::format("forest|{}", size))) pending.forests.push_back(size);
  if (run.config.popping.enabled && session.hasMesh())
    for (const char* path : {"dolly", "orbit"})
      if (!store.has(v.prefix + "popping|" + path)) pending.popping.emplace_back(path);
  return pending;
}

void runViews(RunContext& run, TreeSession& session, const VariantRun& v, Method& method,
              const std::vector<const EvalView*>& views) {
  const RenderSettings& render = run.config.views.render;
  ProgressBar progress(fmt::format("{} {} views", session.label(), v.variant.label), views.size());
  for (const EvalView* view : views) {
    const FlipReference& expected = session.scoredReference(*view);
    DrawnStats drawn;
    const ImageRgba8 image = run.harness.display(
        run.harness.renderLinearAt(method, view->camera, view->width, view->height, &drawn));
    const ImageMetrics metrics = compareImages(expected, image);
    if (run.options.saveImages) {
      writePng(run.options.outDirectory / "images" / safeName(session.label()) /
                   safeName(v.variant.label) / (view->key + ".png"),
               withOpaqueAlpha(image));
    }
    ViewRecord record = v.record<ViewRecord>();
    record.ring = view->ring;
    record.fovDegrees = view->camera.fovYDegrees;
    record.distance = view->distance;
    record.elevation = view->elevation;
    record.azimuth = view->azimuth;
    record.captureView = view->captureView;
    record.psnr = metrics.psnr;
    record.psnrFrame = metrics.psnrFrame;
    record.ssim = metrics.ssim;
    record.flip = metrics.flip;
    record.coverageError = metrics.coverageError;
    record.unionPixels = metrics.unionPixels;
    record.resolution = {view->width, view->height};
    record.supersample = render.supersample;
    record.drawn = drawnRecord(drawn);
    record.shading = render.shading == Shading::kLit ? "lit" : "unlit";
    record.shadows = render.shadows;
    run.store.append(std::move(record), v.prefix + "view|" + view->key);
    progress.advance();
  }
}

}  // namespace canopy
