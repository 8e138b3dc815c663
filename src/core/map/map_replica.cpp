#include "binloop/map/map_replica.h"

#include <algorithm>
#include <unordered_set>

namespace binloop {

namespace {
const std::vector<SlamKeyframeId> kNone;

bool madeBefore(SlamKeyframeId a, SlamKeyframeId b) {
  return counterOf(a) != counterOf(b) ? counterOf(a) < counterOf(b) : a < b;
}

// Observer lists are kept in the order their keyframes were made: then a re-sent keyframe with the points it
// held (every keyframe of a corrected whole map, mostly) is only copied, not relinked. Nothing reads meaning
// into the order (Tracker::sightingKeyframes chooses by range); it only has to be one that costs nothing.
void insertObserver(std::vector<SlamKeyframeId>& v, SlamKeyframeId k) {
  auto at = std::lower_bound(v.begin(), v.end(), k, madeBefore);
  if (at == v.end() || *at != k) v.insert(at, k);
}
}  // namespace

void MapReplica::unlinkKeyframe(const msg::KeyframeState& kf) {
  for (MapPointId p : kf.point_ids) {
    if (p == kNoId) continue;
    auto it = observers_.find(p);
    if (it == observers_.end()) continue;
    auto& v = it->second;
    auto at = std::lower_bound(v.begin(), v.end(), kf.id, madeBefore);
    if (at != v.end() && *at == kf.id) v.erase(at);
    if (v.empty()) observers_.erase(it);
  }
}

void MapReplica::linkKeyframe(const msg::KeyframeState& kf) {
  for (MapPointId p : kf.point_ids) {
    if (p == kNoId) continue;
    insertObserver(observers_[p], kf.id);
  }
}

void MapReplica::upsertKeyframe(const msg::KeyframeState& kf) {
  if (counterOf(kf.id) > counterOf(last_keyframe_)) last_keyframe_ = kf.id;
  auto it = map_.keyframes().find(kf.id);
  if (it != map_.keyframes().end() && it->second.point_ids == kf.point_ids) {
    // The points it holds (a pose refined, the whole map corrected): held ids are resolved already and the
    // lists name it where they should. Most keyframes of a correction's whole map come so, and relinking
    // each one's hundreds of points cost tracking 100-400 ms a correction on route 00.
    it->second = kf;
    return;
  }
  if (it != map_.keyframes().end()) {
    unlinkKeyframe(it->second);
    it->second = kf;
  } else {
    it = map_.keyframes().emplace(kf.id, kf).first;
  }
  // Ids the sender did not know were fused yet are mapped to the kept point.
  for (MapPointId& p : it->second.point_ids) {
    if (p != kNoId) p = resolve(p);
  }
  linkKeyframe(it->second);
}

void MapReplica::upsertPoint(const msg::MapPoint& p) {
  if (map_.wasFused(p.id)) return;  // fused away meanwhile: the kept point stands for it
  map_.points()[p.id] = p;
}

void MapReplica::removePoint(MapPointId id) {
  map_.points().erase(id);
  auto it = observers_.find(id);
  if (it == observers_.end()) return;
  for (SlamKeyframeId k : it->second) {
    auto kf = map_.keyframes().find(k);
    if (kf == map_.keyframes().end()) continue;
    for (MapPointId& q : kf->second.point_ids)
      if (q == id) q = kNoId;
  }
  observers_.erase(it);
}

void MapReplica::removeKeyframe(SlamKeyframeId id) {
  auto it = map_.keyframes().find(id);
  if (it == map_.keyframes().end()) return;
  unlinkKeyframe(it->second);
  map_.cull(id);
}

void MapReplica::fuse(MapPointId removed, MapPointId kept) {
  // Another stage may name a point that was itself fused meanwhile: merge what it has become.
  removed = map_.followed(removed);
  kept = resolve(kept);
  if (removed == kept || kept == kNoId) return;
  map_.recordFusion(removed, kept);
  auto it = observers_.find(removed);
  if (it != observers_.end()) {
    const std::vector<SlamKeyframeId> seen = it->second;
    observers_.erase(it);
    auto& kv = observers_[kept];
    for (SlamKeyframeId k : seen) {
      auto kf = map_.keyframes().find(k);
      if (kf == map_.keyframes().end()) continue;
      // A keyframe that already sees the kept point drops the duplicate (as local mapping does).
      const bool has_kept = std::find(kf->second.point_ids.begin(), kf->second.point_ids.end(), kept) !=
                            kf->second.point_ids.end();
      for (MapPointId& q : kf->second.point_ids)
        if (q == removed) q = has_kept ? kNoId : kept;
      insertObserver(kv, k);
    }
  }
  map_.points().erase(removed);
}

void MapReplica::add(const msg::KeyFrame& kf) {
  for (const auto& p : kf.new_points) upsertPoint(p);
  upsertKeyframe(kf.state);
}

void MapReplica::apply(const msg::LocalMapUpdate& u, bool carry_unsent) {
  const std::unordered_map<SlamKeyframeId, Pose3> moves =
      carry_unsent ? unsentMoves(u) : std::unordered_map<SlamKeyframeId, Pose3>{};
  for (const auto& [removed, kept] : u.fused) fuse(removed, kept);
  for (MapPointId id : u.culled_points) removePoint(id);
  for (SlamKeyframeId id : u.culled_keyframes) removeKeyframe(id);
  for (const auto& p : u.points) upsertPoint(p);
  for (const auto& k : u.keyframes) upsertKeyframe(k);
  if (moves.empty()) return;
  for (const auto& [id, d] : moves) {
    auto it = map_.keyframes().find(id);
    if (it != map_.keyframes().end()) it->second.T_w_c = orthonormalized(d * it->second.T_w_c);
  }
  // The points the unsent keyframes made and `u` does not send move with them. They are a few hundred of
  // the map's 100,000 or more, and each is seen by the keyframe that made it: look among those keyframes'.
  std::unordered_map<MapPointId, const Pose3*> carried;
  for (const auto& [kf_id, d] : moves) {
    const msg::KeyframeState* kf = keyframe(kf_id);
    if (!kf) continue;
    for (MapPointId id : kf->point_ids) {
      auto p = id == kNoId ? map_.points().end() : map_.points().find(id);
      if (p == map_.points().end()) continue;
      auto m = moves.find(p->second.reference);
      if (m != moves.end()) carried.emplace(id, &m->second);
    }
  }
  if (carried.empty()) return;
  for (const auto& p : u.points) carried.erase(p.id);
  for (const auto& [id, d] : carried) msg::moveRigidly(map_.points().at(id), *d);
}

std::unordered_map<SlamKeyframeId, Pose3> MapReplica::unsentMoves(const msg::LocalMapUpdate& u) const {
  std::unordered_map<SlamKeyframeId, Pose3> sent;  // keyframes in `u` -> how they moved here
  for (const auto& k : u.keyframes) {
    auto it = map_.keyframes().find(k.id);
    sent[k.id] =
        it == map_.keyframes().end() ? Pose3::Identity() : Pose3(k.T_w_c * it->second.T_w_c.inverse());
  }
  const std::unordered_set<SlamKeyframeId> culled(u.culled_keyframes.begin(), u.culled_keyframes.end());
  std::unordered_map<SlamKeyframeId, Pose3> moves;
  for (const auto& [id, kf] : map_.keyframes()) {
    if (sent.count(id) || culled.count(id)) continue;
    // Up the parents (unsent ones were made here one on another) to the first the update names; with an
    // ancestor neither side holds, it stays.
    const SlamKeyframeId a =
        map_.firstAncestor(kf.parent, [&](SlamKeyframeId x) { return sent.count(x) > 0; });
    moves.emplace(id, a == kNoId ? Pose3::Identity() : sent.at(a));
  }
  return moves;
}

MapPointId MapReplica::resolve(MapPointId id) const { return map_.resolve(id); }

const msg::MapPoint* MapReplica::point(MapPointId id) const {
  auto it = map_.points().find(resolve(id));
  return it == map_.points().end() ? nullptr : &it->second;
}

const msg::KeyframeState* MapReplica::keyframe(SlamKeyframeId id) const {
  auto it = map_.keyframes().find(id);
  return it == map_.keyframes().end() ? nullptr : &it->second;
}

std::vector<SlamKeyframeId> MapReplica::recentKeyframes(size_t n) const {
  std::vector<SlamKeyframeId> ids;
  for (const auto& [id, kf] : map_.keyframes()) ids.push_back(id);
  std::sort(ids.begin(), ids.end(), [](SlamKeyframeId a, SlamKeyframeId b) {
    return counterOf(a) != counterOf(b) ? counterOf(a) > counterOf(b) : a > b;
  });
  if (ids.size() > n) ids.resize(n);
  return ids;
}

std::vector<SlamKeyframeId> MapReplica::keyframesNear(const Eigen::Vector3d& centre, double radius_m,
                                                      size_t n) const {
  std::vector<std::pair<double, SlamKeyframeId>> near;
  for (const auto& [id, kf] : map_.keyframes()) {
    const double d = (kf.T_w_c.translation() - centre).norm();
    if (d <= radius_m) near.emplace_back(d, id);
  }
  std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    return counterOf(a.second) != counterOf(b.second) ? counterOf(a.second) > counterOf(b.second)
                                                      : a.second > b.second;
  });
  std::vector<SlamKeyframeId> ids;
  for (size_t i = 0; i < near.size() && i < n; ++i) ids.push_back(near[i].second);
  return ids;
}

const std::vector<SlamKeyframeId>& MapReplica::observers(MapPointId id) const {
  auto it = observers_.find(id);
  return it == observers_.end() ? kNone : it->second;
}

}  // namespace binloop
