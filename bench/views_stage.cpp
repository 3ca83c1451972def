// The views stage: every pending view of a variant rendered, scored against the reference and
// recorded; also what a variant still has to do (pendingWork).
#include <fmt/format.h>

#include "bench/stages.h"
#include "common/metrics.h"
#include "common/progress.h"

namespace canopy {

nlohmann::json drawnJson(const DrawnStats& drawn) {
  return {{"primitives", drawn.counts.primitives},
          {"fragments", drawn.counts.fragments},
          {"leaf_geometry_fraction", drawn.leafGeometryFraction}};
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
      if (!store.has(v.prefix + "popping|" + path)) pending.popping.push_back(path);
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
    nlohmann::json record = v.common;
    record.update(view->fields);
    record.update({{"kind", "view"},
                   {"params", v.params},
                   {"psnr", metrics.psnr},
                   {"psnr_frame", metrics.psnrFrame},
                   {"ssim", metrics.ssim},
                   {"flip", metrics.flip},
                   {"coverage_error", metrics.coverageError},
                   {"union_pixels", metrics.unionPixels},
                   {"resolution", {view->width, view->height}},
                   {"supersample", render.supersample},
                   {"drawn", drawnJson(drawn)},
                   {"shading", render.shading == Shading::kLit ? "lit" : "unlit"},
                   {"shadows", render.shadows}});
    run.store.append(record, v.prefix + "view|" + view->key);
    progress.advance();
  }
}

}  // namespace canopy
