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

BudgetRecord runBudget(RunContext& run, TreeSession& session, const VariantRun& v,
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
    memoryAt[value] = double(baked.record.memory.total) / 1e6;
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
  BudgetRecord record;
  record.mode = budget.memoryMb > 0.0 ? "memory_mb" : "psnr_db";
  record.target = budget.memoryMb > 0.0 ? budget.memoryMb : budget.psnrDb;
  record.tolerance = budget.tolerance;
  record.parameter = knob.parameter;
  record.value = knobValue(knob, search.value);
  record.measured = search.measured;
  record.memoryMb = memoryAt[search.value];
  record.reached = search.reached;
  record.steps = search.steps;
  for (const auto& [value, measured] : search.trace)
    record.trace.push_back({knobValue(knob, value), measured, memoryAt[value]});
  return record;
}

}  // namespace canopy
