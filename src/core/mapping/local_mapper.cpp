#include "binloop/mapping/local_mapper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>
#include <unordered_set>

#include "binloop/map/ancestors.h"
#include "binloop/map/fused_points.h"
#include "binloop/map/keypoint_geometry.h"
#include "binloop/map/point_projection.h"

namespace binloop {

namespace {

double msSinceT(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

LocalMapper::LocalMapper(const LocalMapperParams& p) : p_(p) {}

MapPointId LocalMapper::resolve(MapPointId id) const {
  id = followFusions(replaced_, id);
  return pts_.count(id) ? id : kNoId;
}

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
    const KF& kf = kfs_.at(kid);
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
  if (kfs_.count(in.id) || culled_.count(in.id))
    throw std::invalid_argument("keyframe " + std::to_string(in.id) +
                                " is already in the map (its id was issued " +
                                "again: a tracker restarted without mapping?); refused");
  for (const msg::MapPoint& np : in.new_points)
    if (np.id == kNoId || pts_.count(np.id) || replaced_.count(np.id))
      throw std::invalid_argument("keyframe " + std::to_string(in.id) + ": new map point " +
                                  std::to_string(np.id) + " is 0 or already in the map; refused");
  if (scales_.levels() == 0) scales_ = ScalePyramid(in.scale_factor, in.levels);
  camera_ = in.camera;
  // Made before a loop correction tracking had not heard of yet: it moves as its parent did.
  const bool is_late = in.corrections_seen < history_.applied();
  const Pose3 late = is_late ? history_.adopt(in.corrections_seen, in.id, in.state.parent,
                                              [this](SlamKeyframeId a) {
                                                auto c = culled_.find(a);
                                                return c == culled_.end() ? kNoId : c->second.first;
                                              })
                             : Pose3::Identity();
  KF& kf = kfs_[in.id];
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
    MP& mp = pts_[np.id];
    mp.state = np;
    if (is_late) {
      mp.state.p_w = late * np.p_w;
      mp.state.normal = (late.linear().cast<float>() * np.normal).normalized();
    }
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
    MP& mp = pts_.at(id);
    if (mp.obs.count(kf.state.id)) continue;  // two keypoints matched to one point after a fusion
    addObservation(mp, kf, static_cast<int>(i));
    touched_.push_back(id);
  }
  for (MapPointId id : created) {
    MP& mp = pts_.at(id);
    if (mp.obs.empty()) {
      pts_.erase(id);
      continue;
    }
    updatePointShape(mp);
  }
  for (MapPointId id : touched_)
    if (pts_.count(id)) updatePointShape(pts_.at(id));
  updateConnections(kf);
}

void LocalMapper::updateConnections(KF& kf) {
  std::map<SlamKeyframeId, int> w;
  for (MapPointId id : kf.state.point_ids) {
    if (id == kNoId) continue;
    for (const auto& [k, idx] : pts_.at(id).obs)
      if (k != kf.state.id) ++w[k];
  }
  // Old edges of this keyframe go, then the new ones are written on both sides.
  for (const auto& [k, c] : kf.weights) {
    auto it = kfs_.find(k);
    if (it != kfs_.end()) it->second.weights.erase(kf.state.id);
  }
  kf.weights = w;
  for (const auto& [k, c] : w) kfs_.at(k).weights[kf.state.id] = c;
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
    KF& o = kfs_.at(e.id);
    o.state.covisible = covisible(o);
  }
  // Spanning tree: the first time, the keyframe with most shared points becomes the parent.
  if (kf.state.id != first_kf_ && !kf.state.covisible.empty() &&
      (kf.state.parent == kNoId || !kfs_.count(kf.state.parent) || kf.state.parent == kf.state.id))
    kf.state.parent = kf.state.covisible.front().id;
  if (kf.state.parent != kNoId && !kfs_.count(kf.state.parent)) kf.state.parent = kNoId;
}

void LocalMapper::removePoint(MapPointId id) {
  auto it = pts_.find(id);
  if (it == pts_.end()) return;
  for (const auto& [k, idx] : it->second.obs) {
    auto kf = kfs_.find(k);
    if (kf != kfs_.end()) kf->second.state.point_ids[idx] = kNoId;
  }
  pts_.erase(it);
}

void LocalMapper::cullRecentPoints(msg::LocalMapUpdate& u) {
  std::deque<MapPointId> keep;
  for (MapPointId id : recent_) {
    auto it = pts_.find(id);
    if (it == pts_.end()) continue;
    const uint64_t age = seq_ - it->second.first_seq;
    if (age >= static_cast<uint64_t>(p_.cull_after_keyframes) &&
        static_cast<int>(it->second.obs.size()) < p_.cull_min_observers) {
      removePoint(id);
      u.culled_points.push_back(id);
    } else if (age < static_cast<uint64_t>(p_.cull_after_keyframes) + 1) {
      keep.push_back(id);
    }
  }
  recent_.swap(keep);
}

std::vector<SlamKeyframeId> LocalMapper::neighbors(const KF& kf, int n) const {
  std::vector<SlamKeyframeId> out;
  for (const auto& e : kf.state.covisible) {
    if (static_cast<int>(out.size()) >= n) break;
    out.push_back(e.id);
  }
  return out;
}

void LocalMapper::createNewPoints(KF& kf, msg::LocalMapUpdate& u) {
  const auto t0 = std::chrono::steady_clock::now();
  for (SlamKeyframeId k : neighbors(kf, p_.triangulate_neighbors)) {
    KF& o = kfs_.at(k);
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
      MP& mp = pts_[id];
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
  u.triangulation_ms = msSinceT(t0);
}

void LocalMapper::replacePoint(MapPointId removed, MapPointId kept, msg::LocalMapUpdate& u) {
  if (removed == kept) return;
  MP& gone = pts_.at(removed);
  MP& stay = pts_.at(kept);
  for (const auto& [k, idx] : gone.obs) {
    KF& kf = kfs_.at(k);
    if (stay.obs.count(k)) {
      kf.state.point_ids[idx] = kNoId;
    } else {
      addObservation(stay, kf, idx);
    }
  }
  pts_.erase(removed);
  replaced_[removed] = kept;
  u.fused.emplace_back(removed, kept);
  touched_.push_back(kept);
}

std::vector<MapPointId> LocalMapper::pointsOf(const std::vector<SlamKeyframeId>& keyframes) const {
  std::vector<MapPointId> out;
  std::unordered_set<MapPointId> seen;
  for (SlamKeyframeId k : keyframes)
    for (MapPointId id : kfs_.at(k).state.point_ids)
      if (id != kNoId && seen.insert(id).second) out.push_back(id);
  return out;
}

void LocalMapper::fuseInto(KF& t, const std::vector<MapPointId>& points, msg::LocalMapUpdate& u) {
  const Pose3 T_c_w = t.state.T_w_c.inverse();
  for (MapPointId id0 : points) {
    const MapPointId id = resolve(id0);
    if (id == kNoId) continue;
    MP& mp = pts_.at(id);
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
      if (pts_.at(there).obs.size() >= mp.obs.size())
        replacePoint(id, there, u);
      else
        replacePoint(there, id, u);
    }
  }
}

void LocalMapper::fuseWithNeighbors(KF& kf, msg::LocalMapUpdate& u) {
  // Targets: the strongest neighbours and, for each, its 5 strongest (ORB-SLAM2's SearchInNeighbors).
  std::vector<SlamKeyframeId> targets;
  std::unordered_set<SlamKeyframeId> in{kf.state.id};
  for (SlamKeyframeId k : neighbors(kf, p_.fuse_neighbors)) {
    if (in.insert(k).second) targets.push_back(k);
    for (SlamKeyframeId k2 : neighbors(kfs_.at(k), 5))
      if (in.insert(k2).second) targets.push_back(k2);
  }
  std::vector<MapPointId> own;
  for (MapPointId id : kf.state.point_ids)
    if (id != kNoId) own.push_back(id);
  for (SlamKeyframeId k : targets) fuseInto(kfs_.at(k), own, u);
  fuseInto(kf, pointsOf(targets), u);
  for (MapPointId id : kf.state.point_ids)
    if (id != kNoId) touched_.push_back(id);
  for (MapPointId& id : touched_) id = resolve(id);
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  for (MapPointId id : touched_)
    if (id != kNoId) updatePointShape(pts_.at(id));
  updateConnections(kf);
}

void LocalMapper::localBundleAdjustment(KF& kf, msg::LocalMapUpdate& u) {
  // Local keyframes: the new one and its covisible neighbours; fixed: the others that see their points.
  std::vector<SlamKeyframeId> free{kf.state.id};
  for (SlamKeyframeId k : neighbors(kf, p_.local_ba_max_keyframes - 1)) free.push_back(k);
  bundleAdjust(free, p_.ba, u);
}

LocalMapper::BaSetup LocalMapper::makeBaProblem(const std::vector<SlamKeyframeId>& free) const {
  BaSetup b;
  std::unordered_map<SlamKeyframeId, size_t> kf_index;
  std::unordered_map<MapPointId, size_t> pt_index;
  auto addKf = [&](SlamKeyframeId id, bool fixed) {
    if (kf_index.count(id)) return;
    kf_index[id] = b.problem.keyframes.size();
    b.problem.keyframes.push_back(
        {id, orthonormalized(kfs_.at(id).state.T_w_c.inverse()), fixed || id == first_kf_});
  };
  for (SlamKeyframeId k : free) addKf(k, false);
  b.free = b.problem.keyframes.size();
  for (size_t i = 0; i < b.free; ++i)
    for (MapPointId id : kfs_.at(b.problem.keyframes[i].id).state.point_ids)
      if (id != kNoId && !pt_index.count(id)) {
        pt_index[id] = b.problem.points.size();
        b.problem.points.push_back({id, pts_.at(id).state.p_w});
      }
  for (const BaPoint& bp : b.problem.points)
    for (const auto& [k, idx] : pts_.at(bp.id).obs) {
      addKf(k, true);
      const KF& o = kfs_.at(k);
      const msg::KeyPoint& kp = o.keypoints[idx];
      b.problem.observations.push_back(
          {kf_index.at(k), pt_index.at(bp.id), {kp.x, kp.y}, kp.right_x, scales_.inv_sigma2[kp.octave]});
      b.obs_of.emplace_back(bp.id, k);
    }
  return b;
}

void LocalMapper::bundleAdjust(const std::vector<SlamKeyframeId>& free, const LocalBaParams& params,
                               msg::LocalMapUpdate& u) {
  const BaSetup b = makeBaProblem(free);
  if (b.problem.points.empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const LocalBaResult r = binloop::localBundleAdjustment(camera_, b.problem, params, &abort_);
  u.ba_ms = msSinceT(t0);
  u.ba_iterations = r.iterations;
  u.ba_outliers = r.num_outliers;
  for (const BaRefinedKeyframe& rk : r.keyframes)
    kfs_.at(rk.id).state.T_w_c = orthonormalized(rk.T_c_w.inverse());
  for (const BaPoint& bp : r.points) pts_.at(bp.id).state.p_w = bp.p_w;
  removeBaOutliers(b, r, u);
  for (size_t i = 0; i < b.free; ++i) updateConnections(kfs_.at(b.problem.keyframes[i].id));
}

void LocalMapper::removeBaOutliers(const BaSetup& b, const LocalBaResult& r, msg::LocalMapUpdate& u) {
  // Observations that are still outliers are removed from both sides (where both are still in the map:
  // a background BA's map may have changed meanwhile).
  for (size_t i = 0; i < r.outlier.size(); ++i) {
    if (!r.outlier[i]) continue;
    const auto& [pid, k] = b.obs_of[i];
    auto p = pts_.find(pid);
    auto kf = kfs_.find(k);
    if (p == pts_.end() || kf == kfs_.end()) continue;
    auto it = p->second.obs.find(k);
    if (it == p->second.obs.end()) continue;
    kf->second.state.point_ids[it->second] = kNoId;
    p->second.obs.erase(it);
  }
  for (const BaPoint& bp : b.problem.points) {
    auto p = pts_.find(bp.id);
    if (p == pts_.end()) continue;
    if (p->second.obs.empty()) {
      pts_.erase(p);
      u.culled_points.push_back(bp.id);
      continue;
    }
    updatePointShape(p->second);
    touched_.push_back(bp.id);
  }
}

void LocalMapper::removeKeyframe(SlamKeyframeId id) {
  KF& kf = kfs_.at(id);
  for (size_t i = 0; i < kf.state.point_ids.size(); ++i) {
    const MapPointId pid = kf.state.point_ids[i];
    if (pid == kNoId) continue;
    MP& mp = pts_.at(pid);
    mp.obs.erase(id);
    if (mp.obs.empty()) pts_.erase(pid);
  }
  for (const auto& [k, c] : kf.weights) {
    auto it = kfs_.find(k);
    if (it != kfs_.end()) it->second.weights.erase(id);
  }
  // Children of the culled keyframe take its parent (ORB-SLAM2 picks the best covisible candidate; the
  // parent is the simplest choice that keeps the tree connected).
  for (auto& [k, o] : kfs_)
    if (o.state.parent == id) o.state.parent = kf.state.parent;
  auto parent = kfs_.find(kf.state.parent);
  if (parent != kfs_.end())
    culled_[id] = {kf.state.parent, parent->second.state.T_w_c.inverse() * kf.state.T_w_c};
  kfs_.erase(id);
}

void LocalMapper::cullKeyframes(KF& kf, msg::LocalMapUpdate& u) {
  const double close = p_.close_depth_baselines * camera_.baseline_m;
  for (SlamKeyframeId k : neighbors(kf, std::numeric_limits<int>::max())) {
    if (k == first_kf_) continue;
    KF& c = kfs_.at(k);
    int points = 0, redundant = 0;
    for (size_t i = 0; i < c.state.point_ids.size(); ++i) {
      const MapPointId pid = c.state.point_ids[i];
      if (pid == kNoId) continue;
      const float d = c.keypoints[i].depth;
      if (d > close || d < 0) continue;  // stereo: only close points count (ORB-SLAM2)
      ++points;
      const MP& mp = pts_.at(pid);
      if (mp.obs.size() <= 3) continue;
      const int level = c.keypoints[i].octave;
      int others = 0;
      for (const auto& [o, idx] : mp.obs) {
        if (o == k) continue;
        if (kfs_.at(o).keypoints[idx].octave <= level + 1) ++others;
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
        if (kfs_.count(o)) updateConnections(kfs_.at(o));
    }
  }
}

LocalMapper::Output LocalMapper::process(const msg::KeyFrame& in) {
  const auto t0 = std::chrono::steady_clock::now();
  abort_ = false;
  auto u = std::make_shared<msg::LocalMapUpdate>();
  u->sequence = ++updates_;
  u->keyframe = in.id;
  touched_.clear();
  insert(in);
  KF& kf = kfs_.at(in.id);
  cullRecentPoints(*u);
  if (p_.triangulate) createNewPoints(kf, *u);
  if (p_.fuse) fuseWithNeighbors(kf, *u);
  if (p_.local_ba && kfs_.size() > 1) localBundleAdjustment(kf, *u);
  if (p_.cull_keyframes) cullKeyframes(kf, *u);

  // The update: every keyframe of the local window (poses, associations, edges) and every touched point.
  std::unordered_set<SlamKeyframeId> sent;
  auto sendKf = [&](SlamKeyframeId id) {
    auto it = kfs_.find(id);
    if (it != kfs_.end() && sent.insert(id).second) u->keyframes.push_back(it->second.state);
  };
  sendKf(kf.state.id);
  for (SlamKeyframeId k : neighbors(kf, p_.local_ba_max_keyframes)) sendKf(k);
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  for (MapPointId id : touched_) {
    auto it = pts_.find(id);
    if (it != pts_.end()) u->points.push_back(it->second.state);
  }
  u->corrections_seen = history_.applied();
  u->total_ms = msSinceT(t0);

  auto refined = messageOf(kf);
  refined->revision = in.revision + 1;
  return {u, refined};
}

std::vector<LocalMapper::KeyframePose> LocalMapper::keyframes() const {
  std::vector<KeyframePose> out;
  for (const auto& [id, kf] : kfs_) out.push_back({id, kf.frame_index, kf.stamp_s, kf.state.T_w_c});
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

std::vector<Eigen::Vector3d> LocalMapper::pointPositions() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(pts_.size());
  for (const auto& [id, mp] : pts_) out.push_back(mp.state.p_w);
  return out;
}

bool LocalMapper::keyframePose(SlamKeyframeId id, Pose3* T_w_c) const {
  Pose3 T = Pose3::Identity();  // the culled keyframes' poses relative to the held ancestor, composed
  const SlamKeyframeId held = firstAncestor(
      id,
      [&](SlamKeyframeId k) {
        auto c = culled_.find(k);
        if (c == culled_.end()) return kNoId;
        T = c->second.second * T;
        return c->second.first;
      },
      [&](SlamKeyframeId k) { return kfs_.count(k) > 0; });
  if (held == kNoId) return false;
  *T_w_c = kfs_.at(held).state.T_w_c * T;
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
  m->corrections_seen = history_.applied();  // its pose is already in the corrected map's frame
  return m;
}

std::vector<msg::KeyFramePtr> LocalMapper::keyframeMessages() const {
  std::vector<const KF*> kfs;
  for (const auto& [id, kf] : kfs_) kfs.push_back(&kf);
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
  for (const auto& [id, kf] : kfs_) seen(u->tracking_keyframe_ids, id);
  for (const auto& [id, c] : culled_) seen(u->tracking_keyframe_ids, id);
  for (const auto& [id, mp] : pts_) seen(u->tracking_point_ids, id);
  for (const auto& [id, kept] : replaced_) seen(u->tracking_point_ids, id);
  return u;
}

msg::LocalMapUpdatePtr LocalMapper::apply(const msg::Correction& c) {
  const auto t0 = std::chrono::steady_clock::now();
  history_.begin(c.sequence);  // throws for a correction out of order
  stopGlobalBa();              // its result would undo the correction (ORB-SLAM2 stops it too)
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
  auto q = kfs_.find(c.query), m = kfs_.find(c.match);
  if (c.fuse_by_projection && q != kfs_.end() && m != kfs_.end()) {
    std::vector<SlamKeyframeId> near_q{c.query}, near_m{c.match};
    for (SlamKeyframeId k : neighbors(q->second, p_.fuse_neighbors)) near_q.push_back(k);
    for (SlamKeyframeId k : neighbors(m->second, p_.fuse_neighbors)) near_m.push_back(k);
    const std::vector<MapPointId> from_match = pointsOf(near_m);
    for (SlamKeyframeId k : near_q) fuseInto(kfs_.at(k), from_match, *u);
    for (MapPointId& id : touched_) id = resolve(id);
    std::sort(touched_.begin(), touched_.end());
    touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
    for (MapPointId id : touched_)
      if (id != kNoId) updatePointShape(pts_.at(id));
    for (SlamKeyframeId k : near_q) updateConnections(kfs_.at(k));
    u->points_fused_across_loop = static_cast<int>(u->fused.size());
  }

  // Global BA (optional): every keyframe and point, the first keyframe held. In the background it runs on
  // a copy and is merged later (mergeGlobalBa); otherwise here, before the update, so that tracking gets its
  // result with the correction.
  if (p_.global_ba_after_loop) {
    std::vector<SlamKeyframeId> all;
    for (SlamKeyframeId id : ids)
      if (kfs_.count(id)) all.push_back(id);
    if (p_.global_ba_in_background) {
      startGlobalBa(all);
    } else {
      abort_ = false;  // a keyframe that arrives meanwhile cuts it short, as a new loop stops ORB-SLAM2's
      msg::LocalMapUpdate ba;
      bundleAdjust(all, globalBaParams(), ba);
      u->ba_ms = ba.ba_ms;
      u->ba_iterations = ba.ba_iterations;
      u->ba_outliers = ba.ba_outliers;
      u->culled_points = ba.culled_points;
    }
  }

  wholeMapInto(*u);
  u->total_ms = msSinceT(t0);
  return u;
}

void LocalMapper::wholeMapInto(msg::LocalMapUpdate& u) const {
  std::vector<SlamKeyframeId> ids;
  for (const auto& [id, kf] : kfs_) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (SlamKeyframeId id : ids) u.keyframes.push_back(kfs_.at(id).state);
  for (const auto& [id, mp] : pts_) u.points.push_back(mp.state);
  std::sort(u.points.begin(), u.points.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  u.corrections_seen = history_.applied();
}

std::vector<std::pair<SlamKeyframeId, Pose3>> LocalMapper::moveMap(
    const std::unordered_map<SlamKeyframeId, Pose3>& delta,
    const std::unordered_map<MapPointId, Eigen::Vector3d>* placed) {
  // Each keyframe moves by its own delta or, when the mover did not know it yet, by its nearest ancestor's
  // in the spanning tree; a culled keyframe's children went to its parent, and a point whose reference
  // keyframe was culled moves with that keyframe's parent. A point in `placed` goes where it says.
  std::unordered_map<SlamKeyframeId, Pose3> resolved;
  auto parentOf = [&](SlamKeyframeId k) {
    if (auto kf = kfs_.find(k); kf != kfs_.end()) return kf->second.state.parent;
    if (auto cu = culled_.find(k); cu != culled_.end()) return cu->second.first;
    return kNoId;
  };
  auto deltaOf = [&](SlamKeyframeId id) {
    std::vector<SlamKeyframeId> path;  // climbed without a delta: they move with the ancestor that has one
    const SlamKeyframeId known = firstAncestor(id, parentOf, [&](SlamKeyframeId k) {
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
  for (const auto& [id, kf] : kfs_) moved.emplace_back(id, Pose3::Identity());
  std::sort(moved.begin(), moved.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [id, d] : moved) {
    d = deltaOf(id);
    KF& kf = kfs_.at(id);
    kf.state.T_w_c = orthonormalized(d * kf.state.T_w_c);
  }
  for (auto& [id, mp] : pts_) {
    SlamKeyframeId ref = mp.state.reference;
    if (!kfs_.count(ref) && !culled_.count(ref) && !mp.obs.empty()) ref = mp.obs.begin()->first;
    const Pose3 d = deltaOf(ref);
    const Eigen::Vector3d* at = placedAt(id);
    mp.state.p_w = at ? *at : d * mp.state.p_w;
    mp.state.normal = (d.linear().cast<float>() * mp.state.normal).normalized();
  }
  return moved;
}

LocalBaParams LocalMapper::globalBaParams() const {
  LocalBaParams g = p_.ba;
  g.linear_solver = BaLinearSolver::kSparseSchur;  // hundreds of free keyframes
  return g;
}

// The job's thread sees only its own copy of the problem (which keeps the starting poses and points);
// mapping goes on with the map meanwhile.
struct LocalMapper::GlobalBaJob {
  BaSetup setup;
  uint64_t seq_at_start = 0;  // keyframes inserted after it were added meanwhile
  LocalBaResult result;
  std::atomic<bool> abort{false}, done{false};
  std::string failure;  // what it threw, if it did (written before done)
  std::thread thread;
};

void LocalMapper::startGlobalBa(const std::vector<SlamKeyframeId>& keyframes) {
  stopGlobalBa();
  auto job = std::make_unique<GlobalBaJob>();
  job->setup = makeBaProblem(keyframes);
  if (job->setup.problem.points.empty()) return;
  job->seq_at_start = seq_;
  ++global_ba_.started;
  GlobalBaJob* j = job.get();
  job->thread = std::thread([j, params = globalBaParams(), cam = camera_] {
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
  std::unordered_map<MapPointId, Eigen::Vector3d> placed;
  for (size_t i = 0; i < job->result.points.size(); ++i)  // in the problem's order
    if (auto p = pts_.find(start.points[i].id); p != pts_.end() && p->second.state.p_w == start.points[i].p_w)
      placed[start.points[i].id] = job->result.points[i].p_w;
  size_t added = 0;
  for (const auto& [id, kf] : kfs_) added += kf.seq > job->seq_at_start;
  moveMap(delta, &placed);
  removeBaOutliers(job->setup, job->result, *u);
  for (auto& [id, kf] : kfs_) updateConnections(kf);
  const double ms = 1000 * job->result.time_s;
  u->ba_ms = ms;
  u->ba_iterations = job->result.iterations;
  u->ba_outliers = job->result.num_outliers;
  wholeMapInto(*u);
  u->total_ms = msSinceT(t0);
  ++global_ba_.merged;
  global_ba_.last_ms = ms;
  global_ba_.last_keyframes = static_cast<int>(start.keyframes.size());
  global_ba_.last_added_meanwhile = static_cast<int>(added);
  return u;
}

LocalMapper::~LocalMapper() { stopGlobalBa(); }

}  // namespace binloop
