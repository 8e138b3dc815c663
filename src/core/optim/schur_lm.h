#pragma once
// Levenberg-Marquardt for bundle adjustment, points eliminated by the Schur complement (private to
// src/core/optim). Written for this one problem shape instead of asking Ceres: with mono (2-row) and
// stereo (3-row) residuals mixed, Ceres's Schur eliminator has no fixed-size specialisation and falls back
// to dynamic-size blocks, and its automatic Jacobians cost as much again. Here every block has a size known
// at compile time (residual 3, point 3, keyframe 6; a mono residual's third row is zero) and the Jacobians
// are in closed form (linearizeReprojection).
//
// The step is Ceres's and g2o's Levenberg-Marquardt: solve (H + mu D) dx = -g with D = diag(H) (Marquardt's
// scaling, clamped to [1e-6, 1e32]), accept when the cost falls by more than 1e-3 of what the linear
// model promised, then mu *= max(1/3, 1 - (2 rho - 1)^3); on a rejected step mu *= nu, nu *= 2. It starts
// at mu = 1e-4 (Ceres's initial trust radius 1e4) and stops, as Ceres does, when the cost changes by less
// than 1e-6 of itself, the gradient is below 1e-10, or the step below 1e-8 of the variables.
//
// A keyframe moves by a left-multiplied increment (w, rho): T <- [Exp(w) | rho] T, re-anchored after every
// accepted step, so the Jacobians are always taken at w = 0. A robust loss enters as iteratively
// reweighted least squares, weight rho'(chi2): that is what Ceres does with the Huber loss too (its
// second-order correction is zero for a loss whose rho'' <= 0). A step that puts an observed point at or
// behind its camera is rejected.
//
// One thread and a fixed order of every sum: the same input gives bit-identical output.
#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <vector>

#include "binloop/optim/local_bundle_adjustment.h"
#include "binloop/optim/reprojection_costs.h"

namespace binloop::optim_detail {

/// One observation: keyframe and point index, (u, v, u_right), whitening and its outlier threshold.
struct BaTerm {
  uint32_t keyframe = 0, point = 0;
  double obs[3] = {0, 0, 0};
  double sqrt_info = 1;
  bool stereo = false;
  double chi2_max = 0;
  double huber_delta = 0;
};

/// The variables: every keyframe's pose T_c_w and every point.
struct BaState {
  std::vector<Pose3> T;
  std::vector<Eigen::Vector3d> p;
};

struct LmRun {
  int max_iterations = 10;
  bool robust = false;  // Huber on each term's chi2 with its huber_delta; else plain squares
  BaLinearSolver solver = BaLinearSolver::kDenseSchur;
  std::atomic<bool>* abort = nullptr;  // read after every iteration; true stops the run there
};

struct LmOutcome {
  int iterations = 0;  // accepted and rejected steps
  bool aborted = false;
};

/// The term linearised (or, with_jacobians false, only its residual) at the state.
LinearizedReprojection evaluateTerm(const ProjectionConstants& k, const BaTerm& term, const BaState& s,
                                    bool with_jacobians = false);

/// Minimises over the terms marked in `use`; keyframes marked in `fixed` hold still. Only free keyframes
/// seen by a used term, and points seen by one, are written.
LmOutcome solveSchurLm(const ProjectionConstants& k, const std::vector<BaTerm>& terms,
                       const std::vector<bool>& use, const std::vector<bool>& fixed, const LmRun& run,
                       BaState& state);

}  // namespace binloop::optim_detail
