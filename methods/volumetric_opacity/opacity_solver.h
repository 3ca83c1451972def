#pragma once

#include <string>
#include <vector>

#include "methods/volumetric_opacity/opacity_grid.h"

namespace canopy {

struct SolverSettings {
  int maxIterations = 20;         // stop after this many iterations even if not converged
  float convergence = 0.01f;      // converged when no transparency changes by more (§5)
  float cutoff = 0.94f;           // transparency cutoff threshold: cells above become empty (§5)
  int rayStride = 1;              // one ray per stride × stride pixels (1: every pixel, §5)
  float minTransparency = 1e-3f;  // t is kept >= this so log t stays finite
};

struct SolverIteration {
  double rmsTransparency = 0.0;  // RMS over rays of Π t_i − t_p before the iteration's update
  double rmsLog = 0.0;           // the same in log space: Σ q_i − q_p
  float maxChange = 0.0f;        // largest |Δt| the update made
  int activeCells = 0;           // cells with t < 1 after the update
  double seconds = 0.0;
};

struct SolverResult {
  std::string solver;
  std::vector<SolverIteration> iterations;
  double finalRmsTransparency = 0.0;  // of the transparencies kept (the best iterate)
  int rays = 0;
  bool converged = false;
  // Why the iterations stopped: "converged" (no |Δt| above the threshold), "residual_rose" (the
  // log residual of an iterate exceeded the best one's) or "max_iterations"; "ceres: …" for Ceres.
  std::string stopReason;
  int bestIteration = 0;  // the iterate kept: 0 the initialisation, k after the k-th update
  double seconds = 0.0;
};

// §5 and Fig. 5: for every pixel's ray, Q = (log t_i) is projected onto the plane Σ q = log t_p,
// δ_i += w_i (t'_i − t_i); after each pass t_i += δ_i / Σ w_i, and t_i > cutoff becomes 1.
// Each pass first measures the current iterate's log residual RMS(Σq − q_p); the iterate with
// the smallest is kept, and the passes stop once an iterate is worse than the best (the update
// averages the rays' projections, so it is not a descent step and can overshoot).
// Parallel over fixed blocks of pixel rows, reduced in block order: the result does not depend
// on the number of threads.
SolverResult solveByProjection(OpacityGrid& grid, const std::vector<OpacityView>& views,
                               const SolverSettings& settings);

// The same fit as bounded nonlinear least squares (Ceres): minimise Σ_rays (Π t_i − t_p)² with
// t_i in [minTransparency, 1], from the grid's current transparencies; the cutoff is applied to
// the result.
SolverResult solveWithCeres(OpacityGrid& grid, const std::vector<OpacityView>& views,
                            const SolverSettings& settings);

// RMS over the rays of Π t_i − t_p for the grid's current transparencies.
double transparencyResidual(const OpacityGrid& grid, const std::vector<OpacityView>& views,
                            int rayStride);

}  // namespace canopy
