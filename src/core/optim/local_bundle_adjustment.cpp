#include "binloop/optim/local_bundle_adjustment.h"

#include <ceres/iteration_callback.h>
#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <chrono>
#include <memory>

#include "binloop/optim/reprojection_costs.h"
#include "observation_term.h"
#include "optim_checks.h"

namespace binloop {
namespace {

using namespace optim_detail;
constexpr const char* kWho = "localBundleAdjustment";

using Term = ObservationTerm<StereoReprojectionCost::CostFunction, MonoReprojectionCost::CostFunction>;

// ORB-SLAM2's mbAbortBA: Ceres calls this after every iteration (and after evaluating the start, iteration
// 0). Terminating "successfully" keeps the parameters reached so far, as g2o's force-stop flag does.
class AbortCallback : public ceres::IterationCallback {
 public:
  explicit AbortCallback(std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (!flag_->load()) return ceres::SOLVER_CONTINUE;
    fired_ = true;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }
  bool fired() const { return fired_; }

 private:
  std::atomic<bool>* flag_;
  bool fired_ = false;
};

template <typename Item>
void checkUniqueIds(const std::vector<Item>& items, const char* what) {
  std::vector<uint64_t> ids;
  ids.reserve(items.size());
  for (const Item& it : items) ids.push_back(it.id);
  std::sort(ids.begin(), ids.end());
  const auto dup = std::adjacent_find(ids.begin(), ids.end());
  if (dup != ids.end()) fail(kWho, std::string("duplicate ") + what + " id " + std::to_string(*dup));
}

void checkInput(const StereoCamera& camera, const BaProblem& pb, const LocalBaParams& p) {
  if (p.robust_iterations < 0)
    fail(kWho, "parameter robust_iterations must be >= 0 (got " + std::to_string(p.robust_iterations) + ")");
  if (p.refine_iterations < 0)
    fail(kWho, "parameter refine_iterations must be >= 0 (got " + std::to_string(p.refine_iterations) + ")");
  checkPositive(kWho, "chi2_mono", p.chi2_mono);
  checkPositive(kWho, "chi2_stereo", p.chi2_stereo);
  checkPositive(kWho, "huber_delta_mono", p.huber_delta_mono);
  checkPositive(kWho, "huber_delta_stereo", p.huber_delta_stereo);
  for (size_t i = 0; i < pb.keyframes.size(); ++i) {
    checkPose(kWho, pb.keyframes[i].T_c_w,
              "keyframe " + std::to_string(i) + " (id " + std::to_string(pb.keyframes[i].id) + ") T_c_w");
  }
  for (size_t i = 0; i < pb.points.size(); ++i) {
    if (!pb.points[i].p_w.allFinite()) {
      fail(kWho,
           "point " + std::to_string(i) + " (id " + std::to_string(pb.points[i].id) + ") is not finite");
    }
  }
  checkUniqueIds(pb.keyframes, "keyframe");
  checkUniqueIds(pb.points, "point");
  bool any_stereo = false;
  for (size_t i = 0; i < pb.observations.size(); ++i) {
    const BaObservation& o = pb.observations[i];
    const std::string name = "observation " + std::to_string(i);
    if (o.keyframe >= pb.keyframes.size()) {
      fail(kWho, name + ": keyframe index " + std::to_string(o.keyframe) + " out of range (" +
                     std::to_string(pb.keyframes.size()) + " keyframes)");
    }
    if (o.point >= pb.points.size()) {
      fail(kWho, name + ": point index " + std::to_string(o.point) + " out of range (" +
                     std::to_string(pb.points.size()) + " points)");
    }
    checkObservation(kWho, name, nullptr, o.uv, o.u_right, o.inv_sigma2);
    any_stereo |= o.u_right >= 0;
  }
  checkCamera(kWho, camera, any_stereo);
}

// The variables: one 6-vector per keyframe (the increment about its input pose, reprojection_costs.h) and
// one 3-vector per point, each kind in one array. Ceres orders the blocks of an elimination group by
// address, so contiguous storage in input order makes that order (and the result) independent of where the
// allocator put things.
struct Variables {
  std::vector<double> xi;  // 6 per keyframe, zero = input pose
  std::vector<double> p;   // 3 per point
  double* keyframe(size_t i) { return xi.data() + 6 * i; }
  double* point(size_t i) { return p.data() + 3 * i; }
};

struct Stage {
  int iterations = 0;
  bool aborted = false;
};

// Solves over the observations marked in `use`, with the given losses (nullptr: plain squares).
Stage solveStage(const BaProblem& pb, const std::vector<Term>& terms, const std::vector<bool>& use,
                 ceres::LossFunction* loss_stereo, ceres::LossFunction* loss_mono, int max_iterations,
                 BaLinearSolver solver, std::atomic<bool>* abort, Variables& v,
                 std::vector<bool>& kf_touched) {
  Stage stage;
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  std::vector<bool> kf_in(pb.keyframes.size()), pt_in(pb.points.size());
  for (size_t i = 0; i < terms.size(); ++i) {
    if (!use[i]) continue;
    const BaObservation& o = pb.observations[i];
    problem.AddResidualBlock(terms[i].cost(), terms[i].stereo ? loss_stereo : loss_mono,
                             v.keyframe(o.keyframe), v.point(o.point));
    kf_in[o.keyframe] = pt_in[o.point] = true;
  }
  if (problem.NumResidualBlocks() == 0) return stage;

  // Points first (group 0, eliminated), then keyframes; fixed keyframes stay in the ordering but constant.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  bool any_free_keyframe = false;
  for (size_t j = 0; j < pb.points.size(); ++j)
    if (pt_in[j]) ordering->AddElementToGroup(v.point(j), 0);
  for (size_t i = 0; i < pb.keyframes.size(); ++i) {
    if (!kf_in[i]) continue;
    ordering->AddElementToGroup(v.keyframe(i), 1);
    if (pb.keyframes[i].fixed) {
      problem.SetParameterBlockConstant(v.keyframe(i));
    } else {
      kf_touched[i] = true;
      any_free_keyframe = true;
    }
  }

  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  if (any_free_keyframe) {
    options.linear_solver_type =
        solver == BaLinearSolver::kSparseSchur ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
    options.linear_solver_ordering = ordering;
  } else {
    // Structure only: every point is its own 3x3 system; a Schur solver would have nothing left to reduce.
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  }
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;  // determinism: the same input gives bit-identical output
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  std::unique_ptr<AbortCallback> callback;
  if (abort) {
    callback = std::make_unique<AbortCallback>(abort);
    options.callbacks.push_back(callback.get());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  stage.iterations =
      std::max(0, static_cast<int>(summary.iterations.size()) - 1);  // iteration 0 is the start
  stage.aborted = callback && callback->fired();
  return stage;
}

// One reprojection term per observation, stereo or monocular, about its keyframe's initial pose, with its
// outlier threshold.
std::vector<Term> makeTerms(const ProjectionConstants& k, const BaProblem& pb, const LocalBaParams& params) {
  std::vector<Term> terms(pb.observations.size());
  for (size_t i = 0; i < pb.observations.size(); ++i) {
    const BaObservation& o = pb.observations[i];
    const Pose3& T0 = pb.keyframes[o.keyframe].T_c_w;
    if (o.u_right >= 0) {
      terms[i].stereo.reset(StereoReprojectionCost::create(k, T0, o.uv, o.u_right, o.inv_sigma2));
      terms[i].chi2_max = params.chi2_stereo;
    } else {
      terms[i].mono.reset(MonoReprojectionCost::create(k, T0, o.uv, o.u_right, o.inv_sigma2));
      terms[i].chi2_max = params.chi2_mono;
    }
  }
  return terms;
}

}  // namespace

int holdEachUnanchoredGroup(BaProblem& problem) {
  const size_t n = problem.keyframes.size();
  std::vector<size_t> root(n);
  for (size_t i = 0; i < n; ++i) root[i] = i;
  auto find = [&](size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  // Keyframes that see one point are in one group: each observation joins its keyframe to the point's
  // first observer.
  std::vector<size_t> first_seen(problem.points.size(), n);
  for (const BaObservation& o : problem.observations) {
    if (o.keyframe >= n || o.point >= first_seen.size()) continue;  // localBundleAdjustment names these
    size_t& f = first_seen[o.point];
    if (f == n) {
      f = o.keyframe;
    } else {
      const size_t a = find(f), b = find(o.keyframe);
      if (a == b) continue;
      const bool a_older = problem.keyframes[a].id < problem.keyframes[b].id;
      root[a_older ? b : a] = a_older ? a : b;  // each group's root is its oldest keyframe (lowest id)
    }
  }
  std::vector<uint8_t> anchored(n, 0);
  for (size_t i = 0; i < n; ++i)
    if (problem.keyframes[i].fixed) anchored[find(i)] = 1;
  int held = 0;
  for (size_t i = 0; i < n; ++i) {
    if (find(i) != i || anchored[i]) continue;
    problem.keyframes[i].fixed = true;
    ++held;
  }
  return held;
}

LocalBaResult localBundleAdjustment(const StereoCamera& camera, const BaProblem& pb,
                                    const LocalBaParams& params, std::atomic<bool>* abort) {
  const auto t0 = std::chrono::steady_clock::now();
  checkInput(camera, pb, params);
  const ProjectionConstants k(camera);
  const size_t n = pb.observations.size();

  std::vector<Term> terms = makeTerms(k, pb, params);
  ceres::HuberLoss huber_stereo(params.huber_delta_stereo), huber_mono(params.huber_delta_mono);

  Variables v;
  v.xi.assign(6 * pb.keyframes.size(), 0.0);
  v.p.resize(3 * pb.points.size());
  for (size_t j = 0; j < pb.points.size(); ++j) Eigen::Map<Eigen::Vector3d>(v.point(j)) = pb.points[j].p_w;
  std::vector<bool> kf_touched(pb.keyframes.size());

  // Stage 1: Huber, every observation whose point is in front of its camera (Ceres cannot start from a
  // point behind one; those are outliers from the start).
  std::vector<bool> use(n);
  for (size_t i = 0; i < n; ++i) {
    const BaObservation& o = pb.observations[i];
    bool in_front = false;
    terms[i].chi2(v.keyframe(o.keyframe), v.point(o.point), &in_front);
    use[i] = in_front;
  }
  LocalBaResult result;
  if (params.robust_iterations > 0) {
    const Stage s = solveStage(pb, terms, use, &huber_stereo, &huber_mono, params.robust_iterations,
                               params.linear_solver, abort, v, kf_touched);
    result.iterations += s.iterations;
    result.aborted = s.aborted;
  }

  // Stage 2: drop the outliers of stage 1 (chi2 over the threshold or behind the camera), plain squares.
  if (!result.aborted && params.refine_iterations > 0) {
    for (size_t i = 0; i < n; ++i) {
      const BaObservation& o = pb.observations[i];
      use[i] = use[i] && !terms[i].isOutlier(v.keyframe(o.keyframe), v.point(o.point));
    }
    const Stage s = solveStage(pb, terms, use, nullptr, nullptr, params.refine_iterations,
                               params.linear_solver, abort, v, kf_touched);
    result.iterations += s.iterations;
    result.aborted = s.aborted;
  }

  // Read back and judge every observation at the result.
  for (size_t i = 0; i < pb.keyframes.size(); ++i) {
    const BaKeyframe& kf = pb.keyframes[i];
    if (kf.fixed) continue;
    result.keyframes.push_back(
        {i, kf.id, kf_touched[i] ? poseFromIncrement(v.keyframe(i), kf.T_c_w) : kf.T_c_w});
  }
  result.points.resize(pb.points.size());
  for (size_t j = 0; j < pb.points.size(); ++j)
    result.points[j] = {pb.points[j].id, Eigen::Map<const Eigen::Vector3d>(v.point(j))};
  result.outlier.assign(n, false);
  const double xi0[6] = {0, 0, 0, 0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    const BaObservation& o = pb.observations[i];
    result.outlier[i] = terms[i].isOutlier(v.keyframe(o.keyframe), v.point(o.point));
    if (result.outlier[i]) {
      ++result.num_outliers;
      continue;
    }
    bool in_front = false;
    result.initial_cost += 0.5 * terms[i].chi2(xi0, pb.points[o.point].p_w.data(), &in_front);
    result.final_cost += 0.5 * terms[i].chi2(v.keyframe(o.keyframe), v.point(o.point), &in_front);
  }
  result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace binloop
