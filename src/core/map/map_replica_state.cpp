// MapReplica's save/load (a stage's state file, io/state_file.h).
#include <algorithm>

#include "binloop/map/map_replica.h"
#include "binloop/messages/message_state.h"
#include "binloop/util/sorted_keys.h"

namespace binloop {

void MapReplica::save(StateWriter& w) const {
  // Points first: a keyframe loaded before its points would have them resolved to "gone".
  w.put<uint64_t>(map_.points().size());
  for (MapPointId id : sortedKeys(map_.points())) writeMapPoint(w, map_.points().at(id));
  map_.saveFusions(w);
  w.put<uint64_t>(map_.keyframes().size());
  for (SlamKeyframeId id : sortedKeys(map_.keyframes())) writeKeyframeState(w, map_.keyframes().at(id));
  w.put<uint64_t>(last_keyframe_);
}

void MapReplica::load(StateReader& r) {
  *this = MapReplica();
  const uint64_t pts = r.getCount("replica points", 100);
  for (uint64_t i = 0; i < pts; ++i) upsertPoint(readMapPoint(r));
  map_.loadFusions(r, "replica fused points");
  const uint64_t kfs = r.getCount("replica keyframes", 80);
  for (uint64_t i = 0; i < kfs; ++i) upsertKeyframe(readKeyframeState(r));
  last_keyframe_ = r.get<uint64_t>("last keyframe");
}

}  // namespace binloop
