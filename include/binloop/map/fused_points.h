#pragma once
// Map points fused into others: every stage that names a point another stage may have fused meanwhile
// follows the same chain (fused point -> the point that kept it) to what it has become.
#include "binloop/map/ids.h"

namespace binloop {

/// What `id` has become through fusions: `replaced` maps a fused point to the one that kept it; `id` itself
/// when it was never fused. Fusion chains are short; `max_hops` guards a cycle.
template <class Replaced>
MapPointId followFusions(const Replaced& replaced, MapPointId id, int max_hops = 64) {
  for (int hops = 0; hops < max_hops; ++hops) {
    auto it = replaced.find(id);
    if (it == replaced.end()) break;
    id = it->second;
  }
  return id;
}

}  // namespace binloop
