// MapReplica's save/load (a stage's state file, io/state_file.h).
#include <algorithm>

#include "binloop/map/map_replica.h"
#include "binloop/messages/message_state.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {

void MapReplica::save(StateWriter& w) const {
  // Points first: a keyframe loaded before its points would have them resolved to "gone".
  w.put<uint64_t>(points_.size());
  for (MapPointId id : sortedKeys(points_)) writeMapPoint(w, points_.at(id));
  w.put<uint64_t>(replaced_.size());
  for (MapPointId id : sortedKeys(replaced_)) {
    w.put<uint64_t>(id);
    w.put<uint64_t>(replaced_.at(id));
  }
  w.put<uint64_t>(keyframes_.size());
  for (SlamKeyframeId id : sortedKeys(keyframes_)) writeKeyframeState(w, keyframes_.at(id));
  w.put<uint64_t>(last_keyframe_);
}

void MapReplica::load(StateReader& r) {
  *this = MapReplica();
  const uint64_t pts = r.getCount("replica points", 100);
  for (uint64_t i = 0; i < pts; ++i) upsertPoint(readMapPoint(r));
  const uint64_t rep = r.getCount("replica fused points", 16);
  for (uint64_t i = 0; i < rep; ++i) {
    const MapPointId removed = r.get<uint64_t>("fused point");
    replaced_[removed] = r.get<uint64_t>("fused point");
  }
  const uint64_t kfs = r.getCount("replica keyframes", 80);
  for (uint64_t i = 0; i < kfs; ++i) upsertKeyframe(readKeyframeState(r));
  last_keyframe_ = r.get<uint64_t>("last keyframe");
}

}  // namespace binloop
