#pragma once
// The map's bookkeeping, written once for every stage that holds a map: keyframes and points by id, the
// points fused into others (what an id a late message names has become), and the culled keyframes' place in
// the spanning tree (the parent they had and their pose relative to it), so that every holder resolves ids
// and climbs the tree alike. What a holder keeps per keyframe and point is its own: local mapping keypoints,
// descriptors and observations by keypoint (LocalMapper), tracking's replica the states messages carry
// (MapReplica). docs/decisions.md says why the observations are not shared too.
//
// Threads: none of its own; whoever holds one guards it.
#include <unordered_map>

#include "binloop/io/state_file.h"
#include "binloop/map/ancestors.h"
#include "binloop/map/fused_points.h"
#include "binloop/map/ids.h"
#include "binloop/messages/map_state.h"
#include "binloop/messages/message_state.h"
#include "binloop/types/pose.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {

/// A keyframe's state as its holder keeps it: the state itself, or the `state` member of a richer record.
inline const msg::KeyframeState& keyframeStateOf(const msg::KeyframeState& s) { return s; }
template <class K>
auto keyframeStateOf(const K& k) -> decltype((k.state)) {
  return k.state;
}

template <class Keyframe, class Point>
class MapStore {
 public:
  struct Culled {
    SlamKeyframeId parent = kNoId;
    Pose3 T_parent_kf = Pose3::Identity();
  };
  using Keyframes = std::unordered_map<SlamKeyframeId, Keyframe>;
  using Points = std::unordered_map<MapPointId, Point>;
  using Fusions = std::unordered_map<MapPointId, MapPointId>;
  using CulledKeyframes = std::unordered_map<SlamKeyframeId, Culled>;

  Keyframes& keyframes() { return keyframes_; }
  const Keyframes& keyframes() const { return keyframes_; }
  Points& points() { return points_; }
  const Points& points() const { return points_; }

  /// `removed` was merged into `kept`: ids naming it stand for `kept` from now on.
  void recordFusion(MapPointId removed, MapPointId kept) { fusions_[removed] = kept; }
  bool wasFused(MapPointId id) const { return fusions_.count(id) > 0; }
  /// What `id` has become through fusions (itself when never fused), held or not.
  MapPointId followed(MapPointId id) const { return followFusions(fusions_, id); }
  /// The held point `id` stands for now, or kNoId when it was culled or never known.
  MapPointId resolve(MapPointId id) const {
    id = followed(id);
    return points_.count(id) ? id : kNoId;
  }
  const Fusions& fusions() const { return fusions_; }

  /// Erases a held keyframe, which stays known by its place in the tree: its parent and its pose relative
  /// to it (identity when the parent is not held). The holder unlinks it from its points and neighbours
  /// first.
  void cull(SlamKeyframeId id) {
    const auto it = keyframes_.find(id);
    if (it == keyframes_.end()) return;
    const auto& kf = keyframeStateOf(it->second);
    const auto parent = keyframes_.find(kf.parent);
    culled_[id] = {kf.parent, parent == keyframes_.end()
                                  ? Pose3::Identity()
                                  : Pose3(keyframeStateOf(parent->second).T_w_c.inverse() * kf.T_w_c)};
    keyframes_.erase(it);
  }
  /// Records `id` as culled without erasing anything: a tree built by hand (tests) or from a record.
  void recordCulled(SlamKeyframeId id, SlamKeyframeId parent, const Pose3& T_parent_kf) {
    culled_[id] = {parent, T_parent_kf};
  }
  const Culled* culled(SlamKeyframeId id) const {
    auto it = culled_.find(id);
    return it == culled_.end() ? nullptr : &it->second;
  }
  const CulledKeyframes& culledKeyframes() const { return culled_; }
  /// Held now or culled: an id the map has had.
  bool knows(SlamKeyframeId id) const { return keyframes_.count(id) > 0 || culled_.count(id) > 0; }
  /// The parent a culled keyframe had; kNoId for any other.
  SlamKeyframeId culledParent(SlamKeyframeId id) const {
    const Culled* c = culled(id);
    return c ? c->parent : kNoId;
  }
  /// A held keyframe's parent, or the parent a culled one had; kNoId for an unknown id.
  SlamKeyframeId parentOf(SlamKeyframeId id) const {
    if (auto kf = keyframes_.find(id); kf != keyframes_.end()) return keyframeStateOf(kf->second).parent;
    return culledParent(id);
  }
  /// The first of `id` and its ancestors (culled ones included) that `stop` accepts, or kNoId.
  template <class Stop>
  SlamKeyframeId firstAncestor(SlamKeyframeId id, const Stop& stop) const {
    return binloop::firstAncestor(
        id, [this](SlamKeyframeId k) { return parentOf(k); }, stop);
  }

  /// The fusions / culled keyframes in id order (two saves of one store give the same bytes).
  void saveFusions(StateWriter& w) const {
    w.put<uint64_t>(fusions_.size());
    for (MapPointId id : sortedKeys(fusions_)) {
      w.put<uint64_t>(id);
      w.put<uint64_t>(fusions_.at(id));
    }
  }
  void loadFusions(StateReader& r, const char* what) {
    const uint64_t n = r.getCount(what, 16);
    for (uint64_t i = 0; i < n; ++i) {
      const MapPointId removed = r.get<uint64_t>("fused point");
      fusions_[removed] = r.get<uint64_t>("fused point");
    }
  }
  void saveCulled(StateWriter& w) const {
    w.put<uint64_t>(culled_.size());
    for (SlamKeyframeId id : sortedKeys(culled_)) {
      w.put<uint64_t>(id);
      w.put<uint64_t>(culled_.at(id).parent);
      writePose(w, culled_.at(id).T_parent_kf);
    }
  }
  void loadCulled(StateReader& r) {
    const uint64_t n = r.getCount("culled keyframes", 72);
    for (uint64_t i = 0; i < n; ++i) {
      const SlamKeyframeId id = r.get<uint64_t>("culled keyframe");
      const SlamKeyframeId parent = r.get<uint64_t>("culled keyframe parent");
      culled_[id] = {parent, readPose(r, "culled keyframe pose")};
    }
  }

 private:
  Keyframes keyframes_;
  Points points_;
  Fusions fusions_;
  CulledKeyframes culled_;
};

}  // namespace binloop
