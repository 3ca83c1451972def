#include "methods/volumetric_opacity/opacity_solver.h"

#include <ceres/ceres.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <limits>

namespace canopy {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Pixel rows of every view, cut into a fixed number of contiguous blocks.
struct RowBlocks {
  static constexpr int kBlocks = 32;
  std::vector<std::pair<int, int>> rows;  // (view, row)
  size_t begin(int block) const { return rows.size() * size_t(block) / kBlocks; }
  size_t end(int block) const { return rows.size() * size_t(block + 1) / kBlocks; }
};

RowBlocks rowBlocks(const std::vector<OpacityView>& views, int stride) {
  RowBlocks blocks;
  for (size_t v = 0; v < views.size(); ++v)
    for (int y = 0; y < views[v].camera.height(); y += stride) blocks.rows.emplace_back(int(v), y);
  return blocks;
}

float pixelTransparency(const OpacityView& view, int x, int y, float minTransparency) {
  return std::clamp(1.0f - view.image->at(x, y)[3], minTransparency, 1.0f);
}

// Visits every ray (pixel centre, stride) that meets at least one cell still holding opacity.
template <typename Visit>
void forEachRay(const OpacityGrid& grid, const OpacityView& view, int y, int stride,
                float minTransparency, std::vector<RaySegment>& segments, Visit&& visit) {
  for (int x = 0; x < view.camera.width(); x += stride) {
    if (!traceRay(grid, view.camera, float(x) + 0.5f, float(y) + 0.5f, segments)) continue;
    size_t kept = 0;
    for (const RaySegment& s : segments)
      if (grid.transparency[s.cell] < 1.0f) segments[kept++] = s;
    segments.resize(kept);
    if (segments.empty()) continue;
    visit(pixelTransparency(view, x, y, minTransparency), segments);
  }
}

}  // namespace

double transparencyResidual(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                            int rayStride) {
  const RowBlocks blocks = rowBlocks(views, rayStride);
  std::vector<double> sums(RowBlocks::kBlocks, 0.0);
  std::vector<size_t> counts(RowBlocks::kBlocks, 0);
  tbb::parallel_for(0, RowBlocks::kBlocks, [&](int b) {
    std::vector<RaySegment> segments;
    for (size_t r = blocks.begin(b); r < blocks.end(b); ++r) {
      const auto [v, y] = blocks.rows[r];
      forEachRay(grid, views[v], y, rayStride, 0.0f, segments,
                 [&](float tp, const std::vector<RaySegment>& cells) {
                   double product = 1.0;
                   for (const RaySegment& s : cells) product *= grid.transparency[s.cell];
                   sums[b] += (product - tp) * (product - tp);
                   ++counts[b];
                 });
    }
  });
  double sum = 0.0;
  size_t count = 0;
  for (int b = 0; b < RowBlocks::kBlocks; ++b) sum += sums[b], count += counts[b];
  return count ? std::sqrt(sum / double(count)) : 0.0;
}

SolverResult solveByProjection(OpacityGrid& grid, const std::vector<OpacityView>& views,
                               const SolverSettings& settings) {
  const auto start = Clock::now();
  SolverResult result;
  result.solver = "projection";
  const RowBlocks blocks = rowBlocks(views, settings.rayStride);
  const size_t cellCount = grid.cells.size();
  // Per block: δ_i and Σ w_i for every cell (double, so the block order fixes the sum exactly).
  std::vector<std::vector<double>> delta(RowBlocks::kBlocks), weight(RowBlocks::kBlocks);
  for (float& t : grid.transparency) t = std::clamp(t, settings.minTransparency, 1.0f);
  std::vector<float> best = grid.transparency;
  double bestLog = std::numeric_limits<double>::infinity();
  result.stopReason = "max_iterations";
  for (int iteration = 0; iteration <= settings.maxIterations; ++iteration) {
    const auto iterationStart = Clock::now();
    std::vector<double> squared(RowBlocks::kBlocks, 0.0), squaredLog(RowBlocks::kBlocks, 0.0);
    std::vector<int> rays(RowBlocks::kBlocks, 0);
    // The pass after the last update only measures the final iterate.
    const bool project = iteration < settings.maxIterations;
    tbb::parallel_for(0, RowBlocks::kBlocks, [&](int b) {
      if (project) {
        delta[b].assign(cellCount, 0.0);
        weight[b].assign(cellCount, 0.0);
      }
      std::vector<RaySegment> segments;
      for (size_t r = blocks.begin(b); r < blocks.end(b); ++r) {
        const auto [v, y] = blocks.rows[r];
        forEachRay(grid, views[v], y, settings.rayStride, settings.minTransparency, segments,
                   [&](float tp, const std::vector<RaySegment>& cells) {
                     // Fig. 5: project Q onto the plane with normal (1, …, 1) through q_p.
                     double sumLog = 0.0, product = 1.0;
                     for (const RaySegment& s : cells) {
                       sumLog += std::log(double(grid.transparency[s.cell]));
                       product *= grid.transparency[s.cell];
                     }
                     const double qp = std::log(double(tp));
                     const double shift = (qp - sumLog) / double(cells.size());
                     for (const RaySegment& s : cells) {
                       if (!project) break;
                       const double t = grid.transparency[s.cell];
                       const double projected = std::min(1.0, t * std::exp(shift));
                       delta[b][s.cell] += s.weight * (projected - t);  // Eq. 13
                       weight[b][s.cell] += s.weight;
                     }
                     squared[b] += (product - tp) * (product - tp);
                     squaredLog[b] += (sumLog - qp) * (sumLog - qp);
                     ++rays[b];
                   });
      }
    });
    SolverIteration log;
    int rayCount = 0;
    for (int b = 0; b < RowBlocks::kBlocks; ++b) {
      log.rmsTransparency += squared[b];
      log.rmsLog += squaredLog[b];
      rayCount += rays[b];
    }
    log.rmsTransparency = rayCount ? std::sqrt(log.rmsTransparency / rayCount) : 0.0;
    log.rmsLog = rayCount ? std::sqrt(log.rmsLog / rayCount) : 0.0;
    result.rays = rayCount;
    if (log.rmsLog <= bestLog) {
      bestLog = log.rmsLog;
      best = grid.transparency;
      result.bestIteration = iteration;
    } else {
      result.stopReason = "residual_rose";
      spdlog::info(
          "volumetric_opacity: log residual of iterate {} ({:.4f}) above iterate {}'s "
          "({:.4f}): keeping iterate {}",
          iteration, log.rmsLog, result.bestIteration, bestLog, result.bestIteration);
      break;
    }
    if (!project) break;
    // End of the iteration: every cell moves by its normalised δ; above the cutoff it empties.
    for (size_t c = 0; c < cellCount; ++c) {
      if (grid.transparency[c] >= 1.0f) continue;
      double d = 0.0, w = 0.0;
      for (int b = 0; b < RowBlocks::kBlocks; ++b) d += delta[b][c], w += weight[b][c];
      if (w <= 0.0) continue;
      const float before = grid.transparency[c];
      float after = std::clamp(float(before + d / w), settings.minTransparency, 1.0f);
      if (after > settings.cutoff) after = 1.0f;
      log.maxChange = std::max(log.maxChange, std::abs(after - before));
      grid.transparency[c] = after;
    }
    for (float t : grid.transparency) log.activeCells += t < 1.0f ? 1 : 0;
    log.seconds = secondsSince(iterationStart);
    spdlog::info(
        "volumetric_opacity: projection iteration {}: residual RMS(Πt − t_p) {:.4f}, RMS(Σq − "
        "q_p) {:.4f}, max |Δt| {:.4f}, {} cells, {:.2f} s",
        iteration + 1, log.rmsTransparency, log.rmsLog, log.maxChange, log.activeCells,
        log.seconds);
    result.iterations.push_back(log);
    if (log.maxChange < settings.convergence) {
      result.converged = true;
      result.stopReason = "converged";
      result.bestIteration = iteration + 1;  // the change was too small to measure again
      best = grid.transparency;
      break;
    }
  }
  grid.transparency = std::move(best);
  result.finalRmsTransparency = transparencyResidual(grid, views, settings.rayStride);
  result.seconds = secondsSince(start);
  return result;
}

namespace {

// r = Π t_i − t_p over the cells of one ray; ∂r/∂t_i = Π_{j≠i} t_j.
class RayProductCost final : public ceres::CostFunction {
 public:
  RayProductCost(int cells, double tp) : mTp(tp) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->assign(size_t(cells), 1);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const size_t n = parameter_block_sizes().size();
    std::vector<double> prefix(n + 1, 1.0);
    for (size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] * parameters[i][0];
    residuals[0] = prefix[n] - mTp;
    if (jacobians) {
      double suffix = 1.0;
      for (size_t i = n; i-- > 0;) {
        if (jacobians[i]) jacobians[i][0] = prefix[i] * suffix;
        suffix *= parameters[i][0];
      }
    }
    return true;
  }

 private:
  double mTp;
};

}  // namespace

SolverResult solveWithCeres(OpacityGrid& grid, const std::vector<OpacityView>& views,
                            const SolverSettings& settings) {
  const auto start = Clock::now();
  SolverResult result;
  result.solver = "ceres";
  for (float& t : grid.transparency) t = std::clamp(t, settings.minTransparency, 1.0f);
  std::vector<double> values(grid.transparency.begin(), grid.transparency.end());
  ceres::Problem::Options problemOptions;
  problemOptions.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problemOptions);
  const RowBlocks blocks = rowBlocks(views, settings.rayStride);
  std::vector<RaySegment> segments;
  std::vector<double*> parameters;
  // Rays in a fixed order (single thread) so the problem, and Ceres' result, is deterministic.
  for (const auto& [v, y] : blocks.rows) {
    forEachRay(grid, views[v], y, settings.rayStride, settings.minTransparency, segments,
               [&](float tp, const std::vector<RaySegment>& cells) {
                 parameters.clear();
                 for (const RaySegment& s : cells) parameters.push_back(&values[s.cell]);
                 problem.AddResidualBlock(new RayProductCost(int(cells.size()), tp), nullptr,
                                          parameters);
                 ++result.rays;
               });
  }
  for (double& value : values) {
    if (!problem.HasParameterBlock(&value)) continue;
    problem.SetParameterLowerBound(&value, 0, settings.minTransparency);
    problem.SetParameterUpperBound(&value, 0, 1.0);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::CGNR;
  options.max_num_iterations = settings.maxIterations;
  options.function_tolerance = 1e-6;
  options.num_threads = 1;  // deterministic
  options.logging_type = ceres::SILENT;
  struct Logger final : ceres::IterationCallback {
    SolverResult* result;
    size_t rays;
    Clock::time_point last = Clock::now();
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      SolverIteration log;
      log.rmsTransparency = std::sqrt(2.0 * s.cost / double(std::max<size_t>(rays, 1)));
      log.maxChange = float(s.step_norm);
      log.seconds = secondsSince(last);
      last = Clock::now();
      spdlog::info(
          "volumetric_opacity: ceres iteration {}: residual RMS(Πt − t_p) {:.4f}, step "
          "{:.4f}, {:.2f} s",
          s.iteration, log.rmsTransparency, s.step_norm, log.seconds);
      result->iterations.push_back(log);
      return ceres::SOLVER_CONTINUE;
    }
  } logger;
  logger.result = &result;
  logger.rays = size_t(result.rays);
  options.callbacks.push_back(&logger);
  options.update_state_every_iteration = false;
  ceres::Solver::Summary summary;
  if (result.rays > 0) ceres::Solve(options, &problem, &summary);
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.stopReason = "ceres: " + summary.message;
  result.bestIteration = int(summary.iterations.size());
  for (size_t c = 0; c < values.size(); ++c) {
    float t = float(values[c]);
    if (t > settings.cutoff) t = 1.0f;
    grid.transparency[c] = t;
  }
  for (auto& it : result.iterations) {
    it.activeCells = 0;
  }
  int active = 0;
  for (float t : grid.transparency) active += t < 1.0f ? 1 : 0;
  if (!result.iterations.empty()) result.iterations.back().activeCells = active;
  result.finalRmsTransparency = transparencyResidual(grid, views, settings.rayStride);
  result.seconds = secondsSince(start);
  return result;
}

}  // namespace canopy
