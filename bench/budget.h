#pragma once

#include <functional>
#include <vector>

#include "common/config.h"
#include "methods/method.h"

namespace canopy {

// Config "budget": {"memory_mb": X} sets each method's memory knob so its ledger memory is within
// `tolerance` of X (the multi-layer paper's Fig. 13 protocol); {"psnr_db": Y} finds the least
// memory whose mean PSNR over the config's views reaches Y.
struct BudgetSettings {
  double memoryMb = 0.0;
  double psnrDb = 0.0;
  double tolerance = 0.05;
  int maxSteps = 12;

  template <class V>
  void visit(V& v) {
    v("memory_mb", memoryMb, 0.0, 1e6, "> 0: equal memory, each method's knob set to this");
    v("psnr_db", psnrDb, 0.0, 100.0, "> 0: the least memory whose mean PSNR reaches this");
    v("tolerance", tolerance, 0.001, 0.5, "relative tolerance of the memory target");
    v("max_steps", maxSteps, 2, 64, "bakes per method at most");
  }
};

struct KnobSearch {
  double value = 0.0;                            // the knob value chosen
  double measured = 0.0;                         // what the measure gave there
  int steps = 0;                                 // evaluations made
  bool reached = false;                          // memory within tolerance / PSNR target met
  std::vector<std::pair<double, double>> trace;  // (value, measured) in evaluation order
};

// The value whose `measure` is within `tolerance` (relative) of `target`, assuming `measure`
// grows with the value when knob.memoryGrows and shrinks otherwise: from the cheap end of the
// range the value doubles (halves for shrinking knobs) until the target is passed, then a
// bisection (geometric for continuous knobs) closes in. The expensive end of the range is only
// baked when the budget needs it. Out of range: the nearest value tried, reached = false.
KnobSearch bisectToTarget(const MemoryKnob& knob, double target, double tolerance,
                          const std::function<double(double)>& measure, int maxSteps);

// The value giving the least memory whose `quality` reaches `target` (quality assumed to grow
// with memory). reached = false when even the most memory does not reach it.
KnobSearch leastMemoryReaching(const MemoryKnob& knob, double target,
                               const std::function<double(double)>& quality, int maxSteps);

}  // namespace canopy
