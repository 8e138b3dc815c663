#pragma once
// Walking up the spanning tree, culled keyframes included: every stage that moves a keyframe "as its
// nearest known ancestor moved" (late keyframes after a correction, unsent ones in tracking's replica, a
// proposal naming a culled keyframe) climbs the same way.
#include "binloop/map/ids.h"

namespace binloop {

/// The first of `id`, its parent, its parent's parent, ... that `stop` accepts, or kNoId when none does.
/// `parentOf` gives a keyframe's parent (for a culled one, the parent it had), kNoId past the root or for a
/// keyframe it does not know. `max_hops` guards a cycle.
template <class ParentOf, class Stop>
SlamKeyframeId firstAncestor(SlamKeyframeId id, const ParentOf& parentOf, const Stop& stop,
                             int max_hops = 100000) {
  for (int hops = 0; hops < max_hops && id != kNoId; ++hops) {
    if (stop(id)) return id;
    id = parentOf(id);
  }
  return kNoId;
}

}  // namespace binloop
