// Local mapping culling keyframes whose points other keyframes see well enough (ORB-SLAM2's rule).
#include "binloop/mapping/local_mapper.h"

#include <limits>

namespace binloop {

void LocalMapper::removeKeyframe(SlamKeyframeId id) {
  KF& kf = map_.keyframes().at(id);
  for (size_t i = 0; i < kf.state.point_ids.size(); ++i) {
    const MapPointId pid = kf.state.point_ids[i];
    if (pid == kNoId) continue;
    MP& mp = map_.points().at(pid);
    mp.obs.erase(id);
    if (mp.obs.empty()) map_.points().erase(pid);
  }
  for (const auto& [k, c] : kf.weights) {
    auto it = map_.keyframes().find(k);
    if (it != map_.keyframes().end()) it->second.weights.erase(id);
  }
  // Children of the culled keyframe take its parent (ORB-SLAM2 picks the best covisible candidate; the
  // parent is the simplest choice that keeps the tree connected).
  for (auto& [k, o] : map_.keyframes())
    if (o.state.parent == id) o.state.parent = kf.state.parent;
  map_.cull(id);
}

void LocalMapper::cullKeyframes(KF& kf, msg::LocalMapUpdate& u) {
  for (SlamKeyframeId k : neighbors(kf, std::numeric_limits<int>::max())) {
    if (k == first_kf_) continue;
    KF& c = map_.keyframes().at(k);
    int points = 0, redundant = 0;
    for (size_t i = 0; i < c.state.point_ids.size(); ++i) {
      const MapPointId pid = c.state.point_ids[i];
      if (pid == kNoId) continue;
      // Stereo: only close points count (ORB-SLAM2). Its test keeps depth == the bound and 0 too, which no
      // keypoint has (the matcher's depth is bf / disparity > 0, or -1 without a match).
      if (!isCloseDepth(c.keypoints[i].depth, camera_, p_.stereo)) continue;
      ++points;
      const MP& mp = map_.points().at(pid);
      if (mp.obs.size() <= 3) continue;
      const int level = c.keypoints[i].octave;
      int others = 0;
      for (const auto& [o, idx] : mp.obs) {
        if (o == k) continue;
        if (map_.keyframes().at(o).keypoints[idx].octave <= level + 1) ++others;
        if (others >= 3) break;
      }
      if (others >= 3) ++redundant;
    }
    if (points > 0 && redundant > p_.redundant_ratio * points) {
      std::vector<SlamKeyframeId> nb;
      for (const auto& [o, w] : c.weights) nb.push_back(o);
      removeKeyframe(k);
      u.culled_keyframes.push_back(k);
      for (SlamKeyframeId o : nb)
        if (map_.keyframes().count(o)) updateConnections(map_.keyframes().at(o));
    }
  }
}

}  // namespace binloop
