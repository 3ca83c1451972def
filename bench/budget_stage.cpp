// The budget stage: a method's memory knob turned until its ledger memory meets the budget (or
// the least memory whose mean PSNR reaches a target), each trial a full bake and upload.
#include <cmath>
#include <map>

#include <spdlog/spdlog.h>

#include "bench/budget.h"
#include "bench/stages.h"
#include "common/metrics.h"

namespace canopy {
namespace {

nlohmann::json knobValue(const MemoryKnob& knob, double value) {
  return knob.integer ? nlohmann::json(int64_t(std::llround(value))) : nlohmann::json(value);
}

double meanPsnr(RunContext& run, TreeSession& session, Method& method) {
  double sum = 0.0;
  for (const EvalView& view : session.views()) {
    sum += compareImages(session.referenceImage(view),
                         run.harness.display(run.harness.renderLinearAt(method, view.camera,
                                                                        view.width, view.height)))
               .psnr;
  }
  return session.views().empty() ? 0.0 : sum / double(session.views().size());
}

}  // namespace

nlohmann::json runBudget(RunContext& run, TreeSession& session, const VariantRun& v,
                         const MemoryKnob& knob) {
  const BudgetSettings& budget = *run.config.budget;
  std::map<double, double> memoryAt;
  // One trial: the variant with the knob at `value`, under its own ledger owner (released when
  // the trial's method dies).
  const auto trial = [&](double value) {
    MethodVariant variant = v.variant;
    variant.params[knob.parameter] = knobValue(knob, value);
    variant.label += "/budget";
    BakedMethod baked =
        bakeMethod(variant, session.tree(), run.device, session.bakeContext(), std::nullopt);
    memoryAt[value] = baked.record["memory_bytes"]["total"].get<double>() / 1e6;
    return baked;
  };
  spdlog::info("{} on {}: searching {} for the budget", v.variant.label, session.label(),
               knob.parameter);
  KnobSearch search;
  if (budget.memoryMb > 0.0) {
    search = bisectToTarget(
        knob, budget.memoryMb, budget.tolerance,
        [&](double value) {
          trial(value);
          spdlog::info("{}: budget {} = {:g} → {:.2f} MB", v.variant.label, knob.parameter, value,
                       memoryAt[value]);
          return memoryAt[value];
        },
        budget.maxSteps);
  } else {
    search = leastMemoryReaching(
        knob, budget.psnrDb,
        [&](double value) {
          BakedMethod baked = trial(value);
          const double psnr = meanPsnr(run, session, *baked.method);
          spdlog::info("{}: budget {} = {:g} → {:.2f} MB, {:.2f} dB", v.variant.label,
                       knob.parameter, value, memoryAt[value], psnr);
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

}  // namespace canopy
