#include "binloop/optim/local_bundle_adjustment.h"

#include <algorithm>
#include <chrono>

#include "optim_checks.h"
#include "schur_lm.h"

namespace binloop {
namespace {

using namespace optim_detail;
constexpr const char* kWho = "localBundleAdjustment";

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

// One term per observation, stereo or monocular, with its outlier threshold and Huber width.
std::vector<BaTerm> makeTerms(const BaProblem& pb, const LocalBaParams& params) {
  std::vector<BaTerm> terms(pb.observations.size());
  for (size_t i = 0; i < pb.observations.size(); ++i) {
    const BaObservation& o = pb.observations[i];
    BaTerm& t = terms[i];
    t.keyframe = static_cast<uint32_t>(o.keyframe);
    t.point = static_cast<uint32_t>(o.point);
    t.obs[0] = o.uv.x();
    t.obs[1] = o.uv.y();
    t.obs[2] = o.u_right;
    t.sqrt_info = std::sqrt(o.inv_sigma2);
    t.stereo = o.u_right >= 0;
    t.chi2_max = t.stereo ? params.chi2_stereo : params.chi2_mono;
    t.huber_delta = t.stereo ? params.huber_delta_stereo : params.huber_delta_mono;
  }
  return terms;
}

/// Behind the camera, or chi2 above the threshold (or not a number).
bool isOutlier(const LinearizedReprojection& e, const BaTerm& t) {
  return optim_detail::isOutlier(e.in_front, e.chi2, t.chi2_max);
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
  const std::vector<BaTerm> terms = makeTerms(pb, params);

  BaState start;
  for (const BaKeyframe& kf : pb.keyframes) start.T.push_back(kf.T_c_w);
  for (const BaPoint& p : pb.points) start.p.push_back(p.p_w);
  BaState s = start;
  std::vector<bool> fixed(pb.keyframes.size());
  for (size_t i = 0; i < pb.keyframes.size(); ++i) fixed[i] = pb.keyframes[i].fixed;

  // Stage 1: Huber, every observation whose point is in front of its camera (a solver cannot start from a
  // point behind one; those are outliers from the start).
  std::vector<bool> use(n);
  for (size_t i = 0; i < n; ++i) use[i] = evaluateTerm(k, terms[i], s).in_front;
  LocalBaResult result;
  LmRun run;
  run.solver = params.linear_solver;
  run.abort = abort;
  if (params.robust_iterations > 0) {
    run.max_iterations = params.robust_iterations;
    run.robust = true;
    const LmOutcome o = solveSchurLm(k, terms, use, fixed, run, s);
    result.summary.iterations += o.iterations;
    result.summary.robust_iterations = o.iterations;
    result.aborted = o.aborted;
  }

  // Stage 2: drop the outliers of stage 1 (chi2 over the threshold or behind the camera), plain squares.
  if (!result.aborted && params.refine_iterations > 0) {
    for (size_t i = 0; i < n; ++i) use[i] = use[i] && !isOutlier(evaluateTerm(k, terms[i], s), terms[i]);
    run.max_iterations = params.refine_iterations;
    run.robust = false;
    const LmOutcome o = solveSchurLm(k, terms, use, fixed, run, s);
    result.summary.iterations += o.iterations;
    result.aborted = o.aborted;
  }

  // Read back and judge every observation at the result. A keyframe no term saw is its input, bit for bit;
  // each step multiplies in an exact rotation, so there is no drift worth re-orthonormalising.
  for (size_t i = 0; i < pb.keyframes.size(); ++i)
    if (!pb.keyframes[i].fixed) result.keyframes.push_back({i, pb.keyframes[i].id, s.T[i]});
  result.points.resize(pb.points.size());
  for (size_t j = 0; j < pb.points.size(); ++j) result.points[j] = {pb.points[j].id, s.p[j]};
  result.outlier.assign(n, false);
  for (size_t i = 0; i < n; ++i) {
    const LinearizedReprojection e = evaluateTerm(k, terms[i], s);
    result.outlier[i] = isOutlier(e, terms[i]);
    if (result.outlier[i]) {
      ++result.summary.num_outliers;
      continue;
    }
    result.summary.initial_cost += 0.5 * evaluateTerm(k, terms[i], start).chi2;
    result.summary.final_cost += 0.5 * e.chi2;
  }
  result.summary.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace binloop
