// Local mapping's map points: new ones from a keyframe's stereo and triangulation, recent ones culled when
// too few keyframes see them, duplicates fused across neighbours.
#include "binloop/mapping/local_mapper.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <unordered_set>

#include "binloop/map/keypoint_geometry.h"
#include "binloop/map/point_projection.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

int LocalMapper::observerCount(const MP& mp) const {
  using Count = LocalMapperParams::CullCount;
  if (p_.cull_count == Count::kKeyframes) return static_cast<int>(mp.obs.size());
  const bool close_only = p_.cull_count == Count::kCloseStereoTwice;
  int n = 0;
  for (const auto& [k, idx] : mp.obs) {
    const msg::KeyPoint& kp = map_.keyframes().at(k).keypoints[idx];
    n += hasStereo(kp) && (!close_only || isCloseDepth(kp.depth, camera_, p_.stereo)) ? 2 : 1;
  }
  return n;
}

void LocalMapper::cullRecentPoints(msg::LocalMapUpdate& u) {
  std::deque<MapPointId> keep;
  for (MapPointId id : recent_) {
    auto it = map_.points().find(id);
    if (it == map_.points().end()) continue;
    const uint64_t age = seq_ - it->second.first_seq;
    if (age >= static_cast<uint64_t>(p_.cull_after_keyframes) &&
        observerCount(it->second) < p_.cull_min_observers) {
      removePoint(id);
      u.culled_points.push_back(id);
    } else if (age < static_cast<uint64_t>(p_.cull_after_keyframes) + 1) {
      keep.push_back(id);
    }
  }
  recent_.swap(keep);
}

void LocalMapper::createNewPoints(KF& kf, msg::LocalMapUpdate& u) {
  const auto t0 = std::chrono::steady_clock::now();
  for (SlamKeyframeId k : neighbors(kf, p_.triangulate_neighbors)) {
    KF& o = map_.keyframes().at(k);
    // Closer than the stereo baseline: the stereo pair itself already saw these points with more parallax.
    if ((o.state.T_w_c.translation() - kf.state.T_w_c.translation()).norm() < camera_.baseline_m) continue;
    const EpipolarView va{&kf.state.T_w_c, &camera_, &kf.keypoints, &kf.descriptors, &kf.state.point_ids};
    const EpipolarView vb{&o.state.T_w_c, &camera_, &o.keypoints, &o.descriptors, &o.state.point_ids};
    for (const auto& [i, j] : matchAlongEpipolarLines(va, vb, scales_, p_.epipolar)) {
      Eigen::Vector3d X;
      const TriangulationView ta{&kf.state.T_w_c, &camera_, &kf.keypoints[i]};
      const TriangulationView tb{&o.state.T_w_c, &camera_, &o.keypoints[j]};
      if (triangulatePair(ta, tb, scales_, p_.triangulation, &X) != TriangulationResult::kOk) continue;
      const MapPointId id = point_ids_.next();
      MP& mp = map_.points()[id];
      mp.state.id = id;
      mp.state.p_w = X;
      mp.state.reference = kf.state.id;
      mp.state.descriptor = kf.descriptors[i];
      mp.first_seq = kf.seq;
      addObservation(mp, kf, i);
      addObservation(mp, o, j);
      updatePointShape(mp);
      recent_.push_back(id);
      touched_.push_back(id);
      ++u.points_triangulated;
    }
  }
  u.triangulation_ms = msSince(t0);
}

void LocalMapper::replacePoint(MapPointId removed, MapPointId kept, msg::LocalMapUpdate& u) {
  if (removed == kept) return;
  MP& gone = map_.points().at(removed);
  MP& stay = map_.points().at(kept);
  for (const auto& [k, idx] : gone.obs) {
    KF& kf = map_.keyframes().at(k);
    if (stay.obs.count(k)) {
      kf.state.point_ids[idx] = kNoId;
    } else {
      addObservation(stay, kf, idx);
    }
  }
  map_.points().erase(removed);
  map_.recordFusion(removed, kept);
  u.fused.emplace_back(removed, kept);
  touched_.push_back(kept);
}

void LocalMapper::fuseInto(KF& t, const std::vector<MapPointId>& points, msg::LocalMapUpdate& u) {
  const Pose3 T_c_w = t.state.T_w_c.inverse();
  for (MapPointId id0 : points) {
    const MapPointId id = resolve(id0);
    if (id == kNoId) continue;
    MP& mp = map_.points().at(id);
    if (mp.obs.count(t.state.id)) continue;
    ProjectedPoint pp;  // in front, inside the image, within the distance range, less than 60 deg off
    if (!projectIntoFrame(mp.state, T_c_w, camera_, scales_, &pp)) continue;
    const int level = pp.level;
    const float r = p_.fuse_radius * scales_.scale[level];
    int best = std::numeric_limits<int>::max(), best_i = -1;
    for (int i : t.grid.near(pp.u, pp.v, r, level - 1, level + 1)) {
      const msg::KeyPoint& k = t.keypoints[i];
      bool front = false;
      const double chi2 =
          reprojectionChi2(camera_, T_c_w, mp.state.p_w, k, scales_.inv_sigma2[k.octave], &front);
      if (chi2 > (k.right_x >= 0 ? 7.815 : 5.991)) continue;
      const int d = hamming(mp.state.descriptor, t.descriptors[i]);
      if (d < best) best = d, best_i = i;
    }
    if (best_i < 0 || best > p_.fuse_max_hamming) continue;
    const MapPointId there = t.state.point_ids[best_i];
    if (there == kNoId) {
      addObservation(mp, t, best_i);
      touched_.push_back(id);
    } else if (there != id) {
      // Keep the better-observed point (ORB-SLAM2).
      if (map_.points().at(there).obs.size() >= mp.obs.size()) {
        replacePoint(id, there, u);
      } else {
        replacePoint(there, id, u);
      }
    }
  }
}

void LocalMapper::fuseWithNeighbors(KF& kf, msg::LocalMapUpdate& u) {
  // Targets: the strongest neighbours and, for each, its 5 strongest (ORB-SLAM2's SearchInNeighbors).
  std::vector<SlamKeyframeId> targets;
  std::unordered_set<SlamKeyframeId> in{kf.state.id};
  for (SlamKeyframeId k : neighbors(kf, p_.fuse_neighbors)) {
    if (in.insert(k).second) targets.push_back(k);
    for (SlamKeyframeId k2 : neighbors(map_.keyframes().at(k), 5))
      if (in.insert(k2).second) targets.push_back(k2);
  }
  std::vector<MapPointId> own;
  for (MapPointId id : kf.state.point_ids)
    if (id != kNoId) own.push_back(id);
  for (SlamKeyframeId k : targets) fuseInto(map_.keyframes().at(k), own, u);
  fuseInto(kf, pointsOf(targets), u);
  for (MapPointId id : kf.state.point_ids)
    if (id != kNoId) touched_.push_back(id);
  for (MapPointId& id : touched_) id = resolve(id);
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  for (MapPointId id : touched_)
    if (id != kNoId) updatePointShape(map_.points().at(id));
  updateConnections(kf);
}

}  // namespace binloop
