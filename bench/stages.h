#pragma once

#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/experiment.h"
#include "bench/harness.h"
#include "bench/results_store.h"
#include "bench/runner.h"
#include "bench/tree_session.h"

namespace canopy {

// What every stage of a run reads: the config, the options, where records go, and the GL pieces.
struct RunContext {
  const ExperimentConfig& config;
  const RunOptions& options;
  ResultsStore& store;
  gl::Device& device;
  Harness& harness;
  std::string renderer;  // GL_RENDERER, in bake and forest records
};

// One method variant on one tree: the record keys it writes under and what its records name.
struct VariantRun {
  const MethodVariant& variant;
  std::string tree;
  std::string prefix;     // "<tree>|<variant>|": record keys are prefix + what
  nlohmann::json params;  // effective parameters (from the bake)

  // A record of kind T with the tree, method, variant and parameters filled in.
  template <typename T>
  T record() const {
    T r;
    r.tree = tree;
    r.method = variant.method;
    r.variant = variant.label;
    if constexpr (requires { r.params; }) r.params = params;
    return r;
  }
};

// What a variant still has to do on a tree; a resumed run skips the rest.
struct PendingWork {
  bool bake = true;
  std::vector<const EvalView*> views;
  std::vector<int> forests;
  std::vector<std::string> popping;  // path names
  bool done() const { return !bake && views.empty() && forests.empty() && popping.empty(); }
};
PendingWork pendingWork(const RunContext& run, const TreeSession& session, const VariantRun& v);

// The equal-memory (or PSNR-target) search over the method's memory knob (bench/budget.h);
// returns the bake record's "budget".
BudgetRecord runBudget(RunContext& run, TreeSession& session, const VariantRun& v,
                       const MemoryKnob& knob);

// Renders and scores every pending view against the reference: PSNR, SSIM, FLIP, coverage and
// what was drawn, one kind:"view" record each.
void runViews(RunContext& run, TreeSession& session, const VariantRun& v, Method& method,
              const std::vector<const EvalView*>& views);

// A variant's forest sizes still to time, with its baked method.
struct ForestWork {
  const VariantRun& variant;
  Method* method;
  std::vector<int> sizes;
};

// Times every pending forest size interleaved with the reference, all the tree's variants due at
// that size in one timing, and scores their frames: one kind:"forest" record per variant and size.
void runForests(RunContext& run, TreeSession& session, std::span<const ForestWork> work);

// The popping metric along each pending path, one kind:"popping" record each.
void runPopping(RunContext& run, TreeSession& session, const VariantRun& v, Method& method,
                const std::vector<std::string>& paths);

// What a frame drew, as view and forest records carry it.
DrawnRecord drawnRecord(const DrawnStats& drawn);

}  // namespace canopy
