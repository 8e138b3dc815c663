#include "binloop/tracking/far_keyframe_pose.h"

#include <algorithm>
#include <map>

#include "binloop/map/keypoint_geometry.h"
#include "binloop/optim/rigid_alignment.h"
#include "binloop/util/hash_random.h"

namespace binloop {

namespace {

bool agrees(const StereoCamera& cam, const FarMatch& m, const Pose3& T_w_c, const Pose3& T_c_w,
            const Eigen::Vector3d& x_c, double chi2) {
  bool in_front = false;
  if (reprojectionChi2(cam, T_c_w, m.p_w, m.keypoint, static_cast<float>(m.inv_sigma2), &in_front) <= chi2)
    return true;
  const Eigen::Vector3d x_w = T_w_c * x_c;
  for (const KeyframeSighting& s : m.sightings) {
    if (reprojectionChi2(cam, s.T_c_w, x_w, s.keypoint, static_cast<float>(s.inv_sigma2), &in_front) > chi2)
      return false;
  }
  return true;
}

}  // namespace

FarPoseResult farKeyframePose(const StereoCamera& cam, const std::vector<FarMatch>& matches,
                              const Pose3& prior_T_w_c, const FarPoseParams& p, uint64_t seed) {
  FarPoseResult out;
  const int n = static_cast<int>(matches.size());
  out.inlier.assign(matches.size(), 0);
  if (n < std::max(3, p.min_inliers)) return out;
  std::vector<Eigen::Vector3d> x_c(matches.size());
  for (int i = 0; i < n; ++i) x_c[i] = unprojectKeypoint(matches[i].keypoint, cam);

  auto near_prior = [&](const Pose3& T) {
    return (T.translation() - prior_T_w_c.translation()).norm() <= p.max_offset_m &&
           Eigen::AngleAxisd(prior_T_w_c.linear().transpose() * T.linear()).angle() <=
               p.max_turn_deg * M_PI / 180;
  };
  auto score = [&](const Pose3& T) {
    const Pose3 T_c_w = T.inverse();
    int count = 0;
    for (int i = 0; i < n; ++i) count += agrees(cam, matches[i], T, T_c_w, x_c[i], p.chi2);
    return count;
  };
  HashRng rng(seed);
  Pose3 best_T = prior_T_w_c;
  int best = score(prior_T_w_c);
  for (int it = 0; it < p.iterations; ++it) {
    const int a = rng.below(n), b = rng.below(n), c = rng.below(n);
    if (a == b || b == c || a == c) continue;
    const auto T = hornAlignment({matches[a].p_w, matches[b].p_w, matches[c].p_w}, {x_c[a], x_c[b], x_c[c]});
    if (!T || !near_prior(*T)) continue;
    const int count = score(*T);
    if (count > best) best = count, best_T = *T;
  }
  out.ransac_inliers = best;
  if (best < p.min_inliers) return out;

  // The agreeing matches as a bundle adjustment: their keyframes fixed, the frame and the points free.
  BaProblem ba;
  std::map<uint64_t, size_t> kf_index;
  ba.keyframes.push_back({0, best_T.inverse(), false});  // ids are positions: unique by construction
  std::vector<int> used;
  for (int i = 0; i < n; ++i) {
    if (!agrees(cam, matches[i], best_T, best_T.inverse(), x_c[i], p.chi2)) continue;
    const size_t point = ba.points.size();
    // The frame's own stereo point starts the point: nearer the truth than the map's for the near ones.
    ba.points.push_back({static_cast<uint64_t>(i), best_T * x_c[i]});
    const msg::KeyPoint& k = matches[i].keypoint;
    ba.observations.push_back({0, point, Eigen::Vector2d(k.x, k.y), k.right_x, matches[i].inv_sigma2});
    for (const KeyframeSighting& s : matches[i].sightings) {
      auto [it, fresh] = kf_index.emplace(s.keyframe, ba.keyframes.size());
      if (fresh) ba.keyframes.push_back({ba.keyframes.size(), s.T_c_w, true});
      ba.observations.push_back(
          {it->second, point, Eigen::Vector2d(s.keypoint.x, s.keypoint.y), s.keypoint.right_x, s.inv_sigma2});
    }
    used.push_back(i);
  }
  const LocalBaResult r = localBundleAdjustment(cam, ba);
  out.T_w_c = r.keyframes.front().T_c_w.inverse();
  // A match holds when every one of its observations does.
  std::vector<uint8_t> holds(used.size(), 1);
  size_t o = 0;
  for (size_t k = 0; k < used.size(); ++k) {
    const size_t count = 1 + matches[used[k]].sightings.size();
    for (size_t j = 0; j < count; ++j, ++o) holds[k] &= !r.outlier[o];
  }
  for (size_t k = 0; k < used.size(); ++k) out.inlier[used[k]] = holds[k];
  for (uint8_t h : holds) out.inliers += h;
  out.ok = out.inliers >= p.min_inliers && near_prior(out.T_w_c);
  return out;
}

}  // namespace binloop
