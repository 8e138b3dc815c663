// Local mapping's bundle adjustment: local BA around each keyframe, and the global BA after a loop, run on
// its own thread over a copy of the problem and merged when done.
#include "binloop/mapping/local_mapper.h"

#include <chrono>
#include <thread>

#include "binloop/map/keypoint_geometry.h"
#include "binloop/util/stopwatch.h"
#include "binloop/util/thread_priority.h"
#include "global_ba_job.h"

namespace binloop {

void LocalMapper::localBundleAdjustment(KF& kf, msg::LocalMapUpdate& u) {
  // Local keyframes: the new one and its covisible neighbours; fixed: the others that see their points.
  std::vector<SlamKeyframeId> free{kf.state.id};
  for (SlamKeyframeId k : neighbors(kf, p_.local_ba_max_keyframes - 1)) free.push_back(k);
  const LocalBaResult r = bundleAdjust(free, p_.ba, p_.local_ba_yields ? &abort_ : nullptr, u);
  ++local_ba_.runs;
  local_ba_.cut_short += r.aborted;
}

LocalMapper::BaSetup LocalMapper::makeBaProblem(const std::vector<SlamKeyframeId>& free) const {
  BaSetup b;
  std::unordered_map<SlamKeyframeId, size_t> kf_index;
  std::unordered_map<MapPointId, size_t> pt_index;
  auto addKf = [&](SlamKeyframeId id, bool fixed) {
    if (kf_index.count(id)) return;
    kf_index[id] = b.problem.keyframes.size();
    b.problem.keyframes.push_back(
        {id, orthonormalized(map_.keyframes().at(id).state.T_w_c.inverse()), fixed || id == first_kf_});
  };
  for (SlamKeyframeId k : free) addKf(k, false);
  b.free = b.problem.keyframes.size();
  for (size_t i = 0; i < b.free; ++i) {
    for (MapPointId id : map_.keyframes().at(b.problem.keyframes[i].id).state.point_ids) {
      if (id != kNoId && !pt_index.count(id)) {
        pt_index[id] = b.problem.points.size();
        b.problem.points.push_back({id, map_.points().at(id).state.p_w});
      }
    }
  }
  for (const BaPoint& bp : b.problem.points) {
    for (const auto& [k, idx] : map_.points().at(bp.id).obs) {
      addKf(k, true);
      const KF& o = map_.keyframes().at(k);
      const msg::KeyPoint& kp = o.keypoints[idx];
      b.problem.observations.push_back({kf_index.at(k),
                                        pt_index.at(bp.id),
                                        {kp.x, kp.y},
                                        measuredRightX(kp, camera_, p_.stereo),
                                        scales_.inv_sigma2[kp.octave]});
      b.obs_of.emplace_back(bp.id, k);
    }
  }
  holdEachUnanchoredGroup(b.problem);
  return b;
}

LocalBaResult LocalMapper::bundleAdjust(const std::vector<SlamKeyframeId>& free, const LocalBaParams& params,
                                        std::atomic<bool>* abort, msg::LocalMapUpdate& u) {
  const BaSetup b = makeBaProblem(free);
  if (b.problem.points.empty()) return {};
  LocalBaResult r = binloop::localBundleAdjustment(camera_, b.problem, params, abort);
  reportBa(r.summary, u);
  for (const BaRefinedKeyframe& rk : r.keyframes)
    map_.keyframes().at(rk.id).state.T_w_c = orthonormalized(rk.T_c_w.inverse());
  for (const BaPoint& bp : r.points) map_.points().at(bp.id).state.p_w = bp.p_w;
  removeBaOutliers(b, r, u);
  for (size_t i = 0; i < b.free; ++i) updateConnections(map_.keyframes().at(b.problem.keyframes[i].id));
  return r;
}

void LocalMapper::removeBaOutliers(const BaSetup& b, const LocalBaResult& r, msg::LocalMapUpdate& u) {
  // Observations that are still outliers are removed from both sides (where both are still in the map:
  // a background BA's map may have changed meanwhile).
  for (size_t i = 0; i < r.outlier.size(); ++i) {
    if (!r.outlier[i]) continue;
    const auto& [pid, k] = b.obs_of[i];
    auto p = map_.points().find(pid);
    auto kf = map_.keyframes().find(k);
    if (p == map_.points().end() || kf == map_.keyframes().end()) continue;
    auto it = p->second.obs.find(k);
    if (it == p->second.obs.end()) continue;
    kf->second.state.point_ids[it->second] = kNoId;
    p->second.obs.erase(it);
  }
  for (const BaPoint& bp : b.problem.points) {
    auto p = map_.points().find(bp.id);
    if (p == map_.points().end()) continue;
    if (p->second.obs.empty()) {
      map_.points().erase(p);
      u.culled_points.push_back(bp.id);
      continue;
    }
    updatePointShape(p->second);
    touched_.push_back(bp.id);
  }
}

LocalBaParams LocalMapper::globalBaParams() const {
  LocalBaParams g = p_.ba;
  g.linear_solver = BaLinearSolver::kSparseSchur;  // hundreds of free keyframes
  g.robust_iterations = p_.global_ba_robust_iterations;
  g.refine_iterations = p_.global_ba_refine_iterations;
  return g;
}

void LocalMapper::startGlobalBa(const std::vector<SlamKeyframeId>& keyframes) {
  stopGlobalBa();
  auto job = std::make_unique<GlobalBaJob>();
  job->setup = makeBaProblem(keyframes);
  if (job->setup.problem.points.empty()) return;
  job->seq_at_start = seq_;
  ++global_ba_.started;
  GlobalBaJob* j = job.get();
  job->thread = std::thread([j, params = globalBaParams(), cam = camera_] {
    // Seconds of BA on one core must not slow tracking: on 2 cores at 1x, rendered 00's last loop left
    // tracking 0.4 s behind the camera for 5 s while it ran (2026-12-02-correction-stall.md).
    lowerThisThreadPriority(10);
    // An exception leaving a thread's function ends the process: it is kept and reported at the merge.
    try {
      j->result = binloop::localBundleAdjustment(cam, j->setup.problem, params, &j->abort);
    } catch (const std::exception& e) {
      j->failure = e.what();
    } catch (...) {
      j->failure = "an unknown exception";
    }
    j->done = true;
  });
  gba_ = std::move(job);
}

void LocalMapper::stopGlobalBa() {
  if (!gba_) return;
  gba_->abort = true;
  gba_->thread.join();
  gba_.reset();
  ++global_ba_.aborted;
}

msg::LocalMapUpdatePtr LocalMapper::mergeGlobalBa(bool wait) {
  if (!gba_ || (!wait && !gba_->done)) return nullptr;
  gba_->thread.join();
  std::unique_ptr<GlobalBaJob> job = std::move(gba_);
  if (!job->failure.empty()) {
    ++global_ba_.failed;
    global_ba_.last_failure = job->failure;
    return nullptr;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto u = std::make_shared<msg::LocalMapUpdate>();
  u->sequence = ++updates_;
  u->correction = true;  // tracking takes the whole map, as after a loop
  touched_.clear();
  // Keyframes move by what the BA did to them (applied to their pose now, which local BA may have refined
  // since), those added meanwhile with their spanning-tree ancestor; points the BA held go where it put them
  // unless local BA has moved them since, the others with their reference keyframe.
  const BaProblem& start = job->setup.problem;
  std::unordered_map<SlamKeyframeId, Pose3> delta;
  for (const BaRefinedKeyframe& rk : job->result.keyframes)
    delta[rk.id] = rk.T_c_w.inverse() * start.keyframes[rk.index].T_c_w;
  // A held keyframe stays where it is, not where its ancestor's delta would carry it: a map segment's first
  // keyframe (holdEachUnanchoredGroup) has its parent in the old map.
  for (const BaKeyframe& k : start.keyframes)
    if (k.fixed) delta.emplace(k.id, Pose3::Identity());
  std::unordered_map<MapPointId, Eigen::Vector3d> placed;
  for (size_t i = 0; i < job->result.points.size(); ++i) {  // in the problem's order
    if (auto p = map_.points().find(start.points[i].id);
        p != map_.points().end() && p->second.state.p_w == start.points[i].p_w)
      placed[start.points[i].id] = job->result.points[i].p_w;
  }
  size_t added = 0;
  for (const auto& [id, kf] : map_.keyframes()) added += kf.seq > job->seq_at_start;
  // Recorded as a loop correction is: a keyframe tracking made before this merge reached it moves with it.
  merges_.begin(merges_.applied() + 1);
  for (const auto& [id, d] : moveMap(delta, &placed)) merges_.note(id, d);
  removeBaOutliers(job->setup, job->result, *u);
  for (auto& [id, kf] : map_.keyframes()) updateConnections(kf);
  reportBa(job->result.summary, *u);
  wholeMapInto(*u);
  u->total_ms = msSince(t0);
  ++global_ba_.merged;
  global_ba_.last_added_meanwhile = static_cast<int>(added);
  noteGlobalBa(job->result, start.keyframes.size());
  return u;
}

void LocalMapper::noteGlobalBa(const LocalBaResult& r, size_t keyframes) {
  global_ba_.cut_short += r.aborted;  // only a foreground one: a merged background result is never cut short
  global_ba_.last = r.summary;
  global_ba_.last_keyframes = static_cast<int>(keyframes);
}

void LocalMapper::reportBa(const BaSummary& s, msg::LocalMapUpdate& u) {
  u.ba_ms = s.ms();
  u.ba_iterations = s.iterations;
  u.ba_outliers = s.num_outliers;
}

LocalMapper::~LocalMapper() { stopGlobalBa(); }

}  // namespace binloop
