#include "binloop/optim/pose_optimizer.h"

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <memory>

#include "binloop/optim/reprojection_costs.h"
#include "observation_term.h"
#include "optim_checks.h"

namespace binloop {
namespace {

using namespace optim_detail;
constexpr const char* kWho = "optimizePose";

using Term = ObservationTerm<StereoPoseOnlyCost::CostFunction, MonoPoseOnlyCost::CostFunction>;

void checkInput(const StereoCamera& camera, const Pose3& T_c_w, const std::vector<PoseObservation>& obs,
                const PoseOptimizerParams& p) {
  if (p.rounds < 1) fail(kWho, "parameter rounds must be >= 1 (got " + std::to_string(p.rounds) + ")");
  if (p.iterations_per_round < 1) {
    fail(kWho,
         "parameter iterations_per_round must be >= 1 (got " + std::to_string(p.iterations_per_round) + ")");
  }
  if (p.max_solve_observations < 0 || (p.max_solve_observations > 0 && p.max_solve_observations < 3)) {
    fail(kWho, "parameter max_solve_observations must be 0 (all) or >= 3 (got " +
                   std::to_string(p.max_solve_observations) + ")");
  }
  if (p.robust_rounds < 0)
    fail(kWho, "parameter robust_rounds must be >= 0 (got " + std::to_string(p.robust_rounds) + ")");
  checkPositive(kWho, "chi2_mono", p.chi2_mono);
  checkPositive(kWho, "chi2_stereo", p.chi2_stereo);
  checkPositive(kWho, "huber_delta_mono", p.huber_delta_mono);
  checkPositive(kWho, "huber_delta_stereo", p.huber_delta_stereo);
  bool any_stereo = false;
  for (size_t i = 0; i < obs.size(); ++i) {
    const PoseObservation& o = obs[i];
    checkObservation(kWho, "observation " + std::to_string(i), &o.p_w, o.uv, o.u_right, o.inv_sigma2);
    any_stereo |= o.u_right >= 0;
  }
  checkCamera(kWho, camera, any_stereo);
  checkPose(kWho, T_c_w, "initial pose T_c_w");
}

// One reprojection term per observation, stereo or monocular, with its outlier threshold.
std::vector<Term> makeTerms(const ProjectionConstants& k, const Pose3& T_c_w,
                            const std::vector<PoseObservation>& observations,
                            const PoseOptimizerParams& params) {
  std::vector<Term> terms(observations.size());
  for (size_t i = 0; i < observations.size(); ++i) {
    const PoseObservation& o = observations[i];
    if (o.u_right >= 0) {
      terms[i].stereo.reset(StereoPoseOnlyCost::create(k, T_c_w, o.p_w, o.uv, o.u_right, o.inv_sigma2));
      terms[i].chi2_max = params.chi2_stereo;
    } else {
      terms[i].mono.reset(MonoPoseOnlyCost::create(k, T_c_w, o.p_w, o.uv, o.u_right, o.inv_sigma2));
      terms[i].chi2_max = params.chi2_mono;
    }
  }
  return terms;
}

ceres::Solver::Options solverOptions(const PoseOptimizerParams& params) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = params.iterations_per_round;
  options.num_threads = 1;  // determinism: the same input gives bit-identical output
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

}  // namespace

PoseOptimizationResult optimizePose(const StereoCamera& camera, const Pose3& T_c_w,
                                    const std::vector<PoseObservation>& observations,
                                    const PoseOptimizerParams& params) {
  checkInput(camera, T_c_w, observations, params);
  const ProjectionConstants k(camera);
  const size_t n = observations.size();

  std::vector<Term> terms = makeTerms(k, T_c_w, observations, params);
  ceres::HuberLoss huber_stereo(params.huber_delta_stereo), huber_mono(params.huber_delta_mono);

  // The increment about the initial pose (reprojection_costs.h); zero is the initial pose.
  double xi[6] = {0, 0, 0, 0, 0, 0};

  // Before the first round only points behind the camera sit out: the initial pose may be far enough off
  // that chi2 says nothing yet (ORB-SLAM2 starts with every observation in).
  std::vector<bool> excluded(n);
  for (size_t i = 0; i < n; ++i) {
    bool in_front = false;
    terms[i].chi2(xi, &in_front);
    excluded[i] = !in_front;
  }

  const ceres::Solver::Options options = solverOptions(params);
  PoseOptimizationResult result;
  for (int round = 0; round < params.rounds; ++round) {
    size_t active = 0;
    for (size_t i = 0; i < n; ++i) active += !excluded[i];
    if (active < 3) break;

    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    problem.AddParameterBlock(xi, 6);
    const bool robust = round < params.robust_rounds;
    const size_t cap = static_cast<size_t>(params.max_solve_observations);
    const size_t stride = cap > 0 && active > cap ? (active + cap - 1) / cap : 1;
    size_t seen = 0;
    for (size_t i = 0; i < n; ++i) {
      if (excluded[i] || seen++ % stride != 0) continue;
      ceres::LossFunction* loss = nullptr;
      if (robust) loss = terms[i].stereo ? static_cast<ceres::LossFunction*>(&huber_stereo) : &huber_mono;
      problem.AddResidualBlock(terms[i].cost(), loss, xi);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    result.iterations +=
        std::max(0, static_cast<int>(summary.iterations.size()) - 1);  // iteration 0 is the start
    ++result.rounds_run;

    // Every observation, those left out included, is judged again at the new pose.
    for (size_t i = 0; i < n; ++i) excluded[i] = terms[i].isOutlier(xi);
  }

  // Final classification and costs at the returned pose (identical to the last round's classification).
  const double xi0[6] = {0, 0, 0, 0, 0, 0};
  result.T_c_w = result.rounds_run ? poseFromIncrement(xi, T_c_w) : T_c_w;
  result.outlier.assign(n, false);
  for (size_t i = 0; i < n; ++i) {
    result.outlier[i] = terms[i].isOutlier(xi);
    if (result.outlier[i]) continue;
    ++result.num_inliers;
    bool in_front = false;
    result.initial_cost += 0.5 * terms[i].chi2(xi0, &in_front);
    result.final_cost += 0.5 * terms[i].chi2(xi, &in_front);
  }
  return result;
}

}  // namespace binloop
