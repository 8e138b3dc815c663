// Local mapping applying loop closing's corrections: every keyframe and point moved with its own, or its
// nearest ancestor's, correction.
#include "binloop/mapping/local_mapper.h"

#include <algorithm>
#include <chrono>

#include "binloop/map/ancestors.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

msg::LocalMapUpdatePtr LocalMapper::apply(const msg::Correction& c) {
  const auto t0 = std::chrono::steady_clock::now();
  if (c.sequence <= history_.applied()) return nullptr;  // sent again, and this one had come after all
  history_.begin(c.sequence);                            // throws for a correction out of order
  stopGlobalBa();  // its result would undo the correction (ORB-SLAM2 stops it too)
  auto u = std::make_shared<msg::LocalMapUpdate>();
  u->sequence = ++updates_;
  u->keyframe = c.query;
  u->correction = true;
  touched_.clear();

  std::unordered_map<SlamKeyframeId, Pose3> delta;
  for (const msg::KeyframeCorrection& k : c.keyframes) delta[k.id] = k.T_w_c_after * k.T_w_c_before.inverse();
  std::vector<SlamKeyframeId> ids;
  for (const auto& [id, d] : moveMap(delta, nullptr)) {
    history_.note(id, d);
    ids.push_back(id);
  }

  // Merge what the loop matched, then search the match's neighbourhood for the query's (and back).
  for (const auto& [removed, kept] : c.fused) {
    const MapPointId a = resolve(removed), b = resolve(kept);
    if (a != kNoId && b != kNoId) replacePoint(a, b, *u);
  }
  auto q = map_.keyframes().find(c.query), m = map_.keyframes().find(c.match);
  if (c.fuse_by_projection && q != map_.keyframes().end() && m != map_.keyframes().end()) {
    std::vector<SlamKeyframeId> near_q{c.query}, near_m{c.match};
    for (SlamKeyframeId k : neighbors(q->second, p_.fuse_neighbors)) near_q.push_back(k);
    for (SlamKeyframeId k : neighbors(m->second, p_.fuse_neighbors)) near_m.push_back(k);
    const std::vector<MapPointId> from_match = pointsOf(near_m);
    for (SlamKeyframeId k : near_q) fuseInto(map_.keyframes().at(k), from_match, *u);
    for (MapPointId& id : touched_) id = resolve(id);
    std::sort(touched_.begin(), touched_.end());
    touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
    for (MapPointId id : touched_)
      if (id != kNoId) updatePointShape(map_.points().at(id));
    for (SlamKeyframeId k : near_q) updateConnections(map_.keyframes().at(k));
    u->points_fused_across_loop = static_cast<int>(u->fused.size());
  }

  // Global BA (optional): every keyframe and point, the first keyframe held (and a map segment's first, by
  // holdEachUnanchoredGroup, until a loop joins it). In the background it runs on a copy and is merged later
  // (mergeGlobalBa); otherwise here, before the update, so that tracking gets its result with the correction.
  if (p_.global_ba_after_loop) {
    std::vector<SlamKeyframeId> all;
    for (SlamKeyframeId id : ids)
      if (map_.keyframes().count(id)) all.push_back(id);
    if (p_.global_ba_in_background) {
      startGlobalBa(all);
    } else {
      // A keyframe that arrives meanwhile (the abort flag, cleared by the caller) cuts it short, as a new
      // loop stops ORB-SLAM2's.
      noteGlobalBa(bundleAdjust(all, globalBaParams(), &abort_, *u), all.size());
    }
  }

  wholeMapInto(*u);
  u->total_ms = msSince(t0);
  return u;
}

std::vector<std::pair<SlamKeyframeId, Pose3>> LocalMapper::moveMap(
    const std::unordered_map<SlamKeyframeId, Pose3>& delta,
    const std::unordered_map<MapPointId, Eigen::Vector3d>* placed) {
  // Each keyframe moves by its own delta or, when the mover did not know it yet, by its nearest ancestor's
  // in the spanning tree; a culled keyframe's children went to its parent, and a point whose reference
  // keyframe was culled moves with that keyframe's parent. A point in `placed` goes where it says.
  std::unordered_map<SlamKeyframeId, Pose3> resolved;
  auto deltaOf = [&](SlamKeyframeId id) {
    std::vector<SlamKeyframeId> path;  // climbed without a delta: they move with the ancestor that has one
    const SlamKeyframeId known = map_.firstAncestor(id, [&](SlamKeyframeId k) {
      if (resolved.count(k) || delta.count(k)) return true;
      path.push_back(k);
      return false;
    });
    Pose3 d = Pose3::Identity();
    if (known != kNoId) {
      auto r = resolved.find(known);
      d = r != resolved.end() ? r->second : (resolved[known] = delta.at(known));
    }
    for (SlamKeyframeId p : path) resolved[p] = d;
    return d;
  };
  auto placedAt = [&](MapPointId id) -> const Eigen::Vector3d* {
    if (!placed) return nullptr;
    auto it = placed->find(id);
    return it == placed->end() ? nullptr : &it->second;
  };
  std::vector<std::pair<SlamKeyframeId, Pose3>> moved;
  for (const auto& [id, kf] : map_.keyframes()) moved.emplace_back(id, Pose3::Identity());
  std::sort(moved.begin(), moved.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [id, d] : moved) {
    d = deltaOf(id);
    KF& kf = map_.keyframes().at(id);
    kf.state.T_w_c = orthonormalized(d * kf.state.T_w_c);
  }
  for (auto& [id, mp] : map_.points()) {
    SlamKeyframeId ref = mp.state.reference;
    if (!map_.knows(ref) && !mp.obs.empty()) ref = mp.obs.begin()->first;
    const Pose3 d = deltaOf(ref);
    msg::moveRigidly(mp.state, d);
    if (const Eigen::Vector3d* at = placedAt(id)) mp.state.p_w = *at;
  }
  return moved;
}

}  // namespace binloop
