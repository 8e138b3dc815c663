#pragma once
// A stage's own copy of the map, kept up to date from messages (its own keyframes and LocalMapUpdates,
// loop corrections included: local mapping forwards them as updates). Tracking uses one to find its local
// map; it never reads another stage's memory.
// Fused points are remembered (removed -> kept), so a frame that still names a removed point finds the one
// that replaced it.
#include <unordered_map>
#include <vector>

#include "binloop/map/map_store.h"
#include "binloop/messages/keyframe.h"
#include "binloop/messages/local_map_update.h"

namespace binloop {
class StateWriter;
class StateReader;
}  // namespace binloop

namespace binloop {

class MapReplica {
 public:
  void upsertKeyframe(const msg::KeyframeState& kf);
  void upsertPoint(const msg::MapPoint& p);
  void removePoint(MapPointId id);
  void removeKeyframe(SlamKeyframeId id);
  void fuse(MapPointId removed, MapPointId kept);
  /// A keyframe as its creator sent it: its state and the points made with it.
  void add(const msg::KeyFrame& kf);
  /// `carry_unsent`: `u` is the whole map after a loop correction. Keyframes this replica holds that `u`
  /// does not name were made here and are still on their way to the sender; each moves as its nearest
  /// ancestor in `u` moved, with the points it made, which is what the sender does to them when they
  /// arrive (LocalMapper::insert). Left behind, they would keep the live pose, which rides on the newest
  /// of them, where the loop found the map to be wrong, and every keyframe after would bring that back.
  void apply(const msg::LocalMapUpdate& u, bool carry_unsent = false);

  /// The point an id now stands for (following fusions), or kNoId when it was culled or never known.
  MapPointId resolve(MapPointId id) const;
  const msg::MapPoint* point(MapPointId id) const;  // after resolve; nullptr when gone
  const msg::KeyframeState* keyframe(SlamKeyframeId id) const;
  /// Keyframes whose point_ids name this point (resolved id), in the order they were made: newest last.
  const std::vector<SlamKeyframeId>& observers(MapPointId id) const;

  /// The n most recently made keyframes still in the map, newest first.
  std::vector<SlamKeyframeId> recentKeyframes(size_t n) const;
  /// Keyframes whose camera lies within radius_m of `centre`, nearest first (ties: newer first), at most n.
  std::vector<SlamKeyframeId> keyframesNear(const Eigen::Vector3d& centre, double radius_m, size_t n) const;

  size_t pointCount() const { return map_.points().size(); }
  size_t keyframeCount() const { return map_.keyframes().size(); }
  SlamKeyframeId lastKeyframe() const { return last_keyframe_; }

  /// Its whole content, in id order (two saves of the same replica give the same bytes); load() replaces it.
  void save(StateWriter& w) const;
  void load(StateReader& r);

 private:
  void unlinkKeyframe(const msg::KeyframeState& kf);
  void linkKeyframe(const msg::KeyframeState& kf);
  /// For apply(u, true): each held keyframe that `u` neither names nor culls -> how it moves.
  std::unordered_map<SlamKeyframeId, Pose3> unsentMoves(const msg::LocalMapUpdate& u) const;

  // Culled keyframes keep their parent then: an unsent keyframe made on one is carried as that parent moves.
  // Not saved: a loaded replica has nothing in flight, and a keyframe made after the load names a held
  // parent.
  MapStore<msg::KeyframeState, msg::MapPoint> map_;
  std::unordered_map<MapPointId, std::vector<SlamKeyframeId>> observers_;
  SlamKeyframeId last_keyframe_ = kNoId;
};

}  // namespace binloop
