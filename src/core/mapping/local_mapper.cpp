#include "binloop/mapping/local_mapper.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "binloop/util/stopwatch.h"
#include "global_ba_job.h"

namespace binloop {

LocalMapper::LocalMapper(const LocalMapperParams& p) : p_(p) {}

MapPointId LocalMapper::resolve(MapPointId id) const { return map_.resolve(id); }

void LocalMapper::addObservation(MP& mp, KF& kf, int idx) {
  mp.obs[kf.state.id] = idx;
  kf.state.point_ids[idx] = mp.state.id;
}

void LocalMapper::updatePointShape(MP& mp) {
  // Descriptor: the observation with the least median distance to the others (ORB-SLAM2's
  // ComputeDistinctiveDescriptors). Normal and range: from every observing keyframe.
  std::vector<const Desc256*> ds;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  const KF* ref = nullptr;
  int ref_idx = -1;
  for (const auto& [kid, idx] : mp.obs) {
    const KF& kf = map_.keyframes().at(kid);
    ds.push_back(&kf.descriptors[idx]);
    const Eigen::Vector3d ray = mp.state.p_w - kf.state.T_w_c.translation();
    normal += ray.normalized();
    if (kid == mp.state.reference || !ref) {
      ref = &kf;
      ref_idx = idx;
    }
  }
  if (ds.empty()) return;
  if (ds.size() > 2) {
    int best = std::numeric_limits<int>::max();
    size_t best_i = 0;
    for (size_t i = 0; i < ds.size(); ++i) {
      std::vector<int> d;
      for (size_t j = 0; j < ds.size(); ++j)
        if (j != i) d.push_back(hamming(*ds[i], *ds[j]));
      std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
      if (d[d.size() / 2] < best) {
        best = d[d.size() / 2];
        best_i = i;
      }
    }
    mp.state.descriptor = *ds[best_i];
  }
  mp.state.normal = normal.normalized().cast<float>();
  const double dist = (mp.state.p_w - ref->state.T_w_c.translation()).norm();
  mp.state.max_distance = static_cast<float>(dist * scales_.scale[ref->keypoints[ref_idx].octave]);
  mp.state.min_distance = mp.state.max_distance / scales_.scale.back();
  mp.state.observations = static_cast<uint32_t>(mp.obs.size());
}

void LocalMapper::insert(const msg::KeyFrame& in) {
  if (const std::string bad = msg::keyframeShapeProblem(in); !bad.empty()) throw std::invalid_argument(bad);
  // Ids are never reused: one the map holds (or culled) comes from another tracking session (a tracker
  // restarted while mapping kept its map), and taking it would overwrite a keyframe or point others refer to.
  if (map_.knows(in.id)) {
    throw std::invalid_argument("keyframe " + std::to_string(in.id) +
                                " is already in the map (its id was issued " +
                                "again: a tracker restarted without mapping?); refused");
  }
  for (const msg::MapPoint& np : in.new_points) {
    if (np.id == kNoId || map_.points().count(np.id) || map_.wasFused(np.id)) {
      throw std::invalid_argument("keyframe " + std::to_string(in.id) + ": new map point " +
                                  std::to_string(np.id) + " is 0 or already in the map; refused");
    }
  }
  if (scales_.levels() == 0) scales_ = ScalePyramid(in.scale_factor, in.levels);
  camera_ = in.camera;
  // Made before a loop correction or a global BA merge tracking had not heard of yet: it moves as its parent
  // did (the correction first: a merge follows the loop it was started for).
  const auto up = [this](SlamKeyframeId a) { return map_.culledParent(a); };
  const bool late_for_loop = in.corrections_seen < history_.applied();
  const bool late_for_merge = in.merges_seen < merges_.applied();
  const bool is_late = late_for_loop || late_for_merge;
  Pose3 late = Pose3::Identity();
  if (late_for_loop) late = history_.adopt(in.corrections_seen, in.id, in.state.parent, up);
  if (late_for_merge) late = merges_.adopt(in.merges_seen, in.id, in.state.parent, up) * late;
  KF& kf = map_.keyframes()[in.id];
  kf.state = in.state;
  kf.state.covisible.clear();
  if (is_late) kf.state.T_w_c = orthonormalized(late * kf.state.T_w_c);
  kf.frame_index = in.frame_index;
  kf.stamp_s = in.stamp_s;
  kf.seq = ++seq_;
  kf.keypoints = in.keypoints;
  kf.descriptors = in.descriptors;
  kf.grid = KeypointGrid(kf.keypoints, in.camera.width, in.camera.height);
  if (first_kf_ == kNoId) first_kf_ = in.id;

  std::unordered_set<MapPointId> created;
  for (const msg::MapPoint& np : in.new_points) {
    MP& mp = map_.points()[np.id];
    mp.state = np;
    if (is_late) msg::moveRigidly(mp.state, late);
    mp.first_seq = kf.seq;
    recent_.push_back(np.id);
    created.insert(np.id);
  }
  for (size_t i = 0; i < kf.state.point_ids.size(); ++i) {
    MapPointId id = kf.state.point_ids[i];
    if (id == kNoId) continue;
    id = resolve(id);
    kf.state.point_ids[i] = kNoId;
    if (id == kNoId) continue;  // culled meanwhile
    MP& mp = map_.points().at(id);
    if (mp.obs.count(kf.state.id)) continue;  // two keypoints matched to one point after a fusion
    addObservation(mp, kf, static_cast<int>(i));
    touched_.push_back(id);
  }
  for (MapPointId id : created) {
    MP& mp = map_.points().at(id);
    if (mp.obs.empty()) {
      map_.points().erase(id);
      continue;
    }
    updatePointShape(mp);
  }
  for (MapPointId id : touched_)
    if (map_.points().count(id)) updatePointShape(map_.points().at(id));
  updateConnections(kf);
}

void LocalMapper::updateConnections(KF& kf) {
  std::map<SlamKeyframeId, int> w;
  for (MapPointId id : kf.state.point_ids) {
    if (id == kNoId) continue;
    for (const auto& [k, idx] : map_.points().at(id).obs)
      if (k != kf.state.id) ++w[k];
  }
  // Old edges of this keyframe go, then the new ones are written on both sides.
  for (const auto& [k, c] : kf.weights) {
    auto it = map_.keyframes().find(k);
    if (it != map_.keyframes().end()) it->second.weights.erase(kf.state.id);
  }
  kf.weights = w;
  for (const auto& [k, c] : w) map_.keyframes().at(k).weights[kf.state.id] = c;
  auto covisible = [&](const KF& x) {
    std::vector<msg::CovisibleEdge> e;
    int best = 0;
    SlamKeyframeId best_id = kNoId;
    for (const auto& [k, c] : x.weights) {
      if (c >= p_.covisibility_min) e.push_back({k, static_cast<uint32_t>(c)});
      if (c > best) best = c, best_id = k;
    }
    if (e.empty() && best_id != kNoId) e.push_back({best_id, static_cast<uint32_t>(best)});
    std::stable_sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.weight > b.weight; });
    return e;
  };
  kf.state.covisible = covisible(kf);
  for (const auto& e : kf.state.covisible) {
    KF& o = map_.keyframes().at(e.id);
    o.state.covisible = covisible(o);
  }
  // Spanning tree: the first time, the keyframe with most shared points becomes the parent.
  if (kf.state.id != first_kf_ && !kf.state.covisible.empty() &&
      (kf.state.parent == kNoId || !map_.keyframes().count(kf.state.parent) ||
       kf.state.parent == kf.state.id))
    kf.state.parent = kf.state.covisible.front().id;
  // A keyframe that shares no point (a map segment's first) keeps its tie through a culled parent's nearest
  // held ancestor: it is its only one.
  if (kf.state.parent != kNoId && !map_.keyframes().count(kf.state.parent)) {
    kf.state.parent = map_.firstAncestor(kf.state.parent,
                                         [this](SlamKeyframeId k) { return map_.keyframes().count(k) > 0; });
  }
}

void LocalMapper::removePoint(MapPointId id) {
  auto it = map_.points().find(id);
  if (it == map_.points().end()) return;
  for (const auto& [k, idx] : it->second.obs) {
    auto kf = map_.keyframes().find(k);
    if (kf != map_.keyframes().end()) kf->second.state.point_ids[idx] = kNoId;
  }
  map_.points().erase(it);
}

std::vector<SlamKeyframeId> LocalMapper::neighbors(const KF& kf, int n) const {
  std::vector<SlamKeyframeId> out;
  for (const auto& e : kf.state.covisible) {
    if (static_cast<int>(out.size()) >= n) break;
    out.push_back(e.id);
  }
  return out;
}

std::vector<MapPointId> LocalMapper::pointsOf(const std::vector<SlamKeyframeId>& keyframes) const {
  std::vector<MapPointId> out;
  std::unordered_set<MapPointId> seen;
  for (SlamKeyframeId k : keyframes) {
    for (MapPointId id : map_.keyframes().at(k).state.point_ids)
      if (id != kNoId && seen.insert(id).second) out.push_back(id);
  }
  return out;
}

LocalMapper::Output LocalMapper::process(const msg::KeyFrame& in) {
  const auto t0 = std::chrono::steady_clock::now();
  auto u = std::make_shared<msg::LocalMapUpdate>();
  u->sequence = ++updates_;
  u->keyframe = in.id;
  touched_.clear();
  insert(in);
  KF& kf = map_.keyframes().at(in.id);
  cullRecentPoints(*u);
  if (p_.triangulate) createNewPoints(kf, *u);
  if (p_.fuse) fuseWithNeighbors(kf, *u);
  if (p_.local_ba && map_.keyframes().size() > 1) localBundleAdjustment(kf, *u);
  if (p_.cull_keyframes) cullKeyframes(kf, *u);

  // The update: every keyframe of the local window (poses, associations, edges) and every touched point.
  std::unordered_set<SlamKeyframeId> sent;
  auto sendKf = [&](SlamKeyframeId id) {
    auto it = map_.keyframes().find(id);
    if (it != map_.keyframes().end() && sent.insert(id).second) u->keyframes.push_back(it->second.state);
  };
  sendKf(kf.state.id);
  for (SlamKeyframeId k : neighbors(kf, p_.local_ba_max_keyframes)) sendKf(k);
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  for (MapPointId id : touched_) {
    auto it = map_.points().find(id);
    if (it != map_.points().end()) u->points.push_back(it->second.state);
  }
  stampSeen(*u);
  u->total_ms = msSince(t0);

  auto refined = messageOf(kf);
  refined->revision = in.revision + 1;
  return {u, refined};
}

std::vector<LocalMapper::KeyframePose> LocalMapper::keyframes() const {
  std::vector<KeyframePose> out;
  for (const auto& [id, kf] : map_.keyframes())
    out.push_back({id, kf.frame_index, kf.stamp_s, kf.state.T_w_c});
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

std::vector<Eigen::Vector3d> LocalMapper::pointPositions() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(map_.points().size());
  for (const auto& [id, mp] : map_.points()) out.push_back(mp.state.p_w);
  return out;
}

bool LocalMapper::keyframePose(SlamKeyframeId id, Pose3* T_w_c) const {
  Pose3 T = Pose3::Identity();  // the culled keyframes' poses relative to the held ancestor, composed
  const SlamKeyframeId held = firstAncestor(
      id,
      [&](SlamKeyframeId k) {
        const auto* c = map_.culled(k);
        if (!c) return kNoId;
        T = c->T_parent_kf * T;
        return c->parent;
      },
      [&](SlamKeyframeId k) { return map_.keyframes().count(k) > 0; });
  if (held == kNoId) return false;
  *T_w_c = map_.keyframes().at(held).state.T_w_c * T;
  return true;
}

std::shared_ptr<msg::KeyFrame> LocalMapper::messageOf(const KF& kf) const {
  auto m = std::make_shared<msg::KeyFrame>();
  m->id = kf.state.id;
  m->revision = 1;
  m->frame_index = kf.frame_index;
  m->stamp_s = kf.stamp_s;
  m->camera = camera_;
  m->scale_factor = scales_.factor;
  m->levels = static_cast<uint8_t>(scales_.levels());
  m->keypoints = kf.keypoints;
  m->descriptors = kf.descriptors;
  m->state = kf.state;
  stampSeen(*m);  // its pose is already in the corrected and merged map's frame
  return m;
}

std::vector<msg::KeyFramePtr> LocalMapper::keyframeMessages() const {
  std::vector<const KF*> kfs;
  for (const auto& [id, kf] : map_.keyframes()) kfs.push_back(&kf);
  std::sort(kfs.begin(), kfs.end(), [](const KF* a, const KF* b) { return a->seq < b->seq; });
  std::vector<msg::KeyFramePtr> out;
  for (const KF* kf : kfs) {
    auto m = messageOf(*kf);
    m->resent = true;
    out.push_back(std::move(m));
  }
  return out;
}

msg::LocalMapUpdatePtr LocalMapper::wholeMap() const {
  auto u = std::make_shared<msg::LocalMapUpdate>();
  wholeMapInto(*u);
  u->whole_map = true;
  auto seen = [](uint64_t& highest, uint64_t id) {
    if (issuerOf(id) == IdIssuer::kTracking) highest = std::max(highest, counterOf(id));
  };
  for (const auto& [id, kf] : map_.keyframes()) seen(u->tracking_keyframe_ids, id);
  for (const auto& [id, c] : map_.culledKeyframes()) seen(u->tracking_keyframe_ids, id);
  for (const auto& [id, mp] : map_.points()) seen(u->tracking_point_ids, id);
  for (const auto& [id, kept] : map_.fusions()) seen(u->tracking_point_ids, id);
  return u;
}

void LocalMapper::wholeMapInto(msg::LocalMapUpdate& u) const {
  std::vector<SlamKeyframeId> ids;
  for (const auto& [id, kf] : map_.keyframes()) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (SlamKeyframeId id : ids) u.keyframes.push_back(map_.keyframes().at(id).state);
  for (const auto& [id, mp] : map_.points()) u.points.push_back(mp.state);
  std::sort(u.points.begin(), u.points.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  stampSeen(u);
}

}  // namespace binloop
