#pragma once
// Correction: loop closing -> every stage, after a loop is fused and the pose graph optimised (the loop
// closing issue builds it; the stages apply it already). Like LocalMapUpdate it overwrites the named
// keyframes and points, and it also says which points were merged across the loop.
#include <memory>
#include <utility>
#include <vector>

#include "binloop/messages/map_state.h"

namespace binloop::msg {

struct Correction {
  uint64_t sequence = 0;
  SlamKeyframeId query = kNoId, match = kNoId;  // the loop that caused it
  std::vector<KeyframeState> keyframes;         // corrected poses (and re-associated points)
  std::vector<MapPoint> points;                 // corrected positions
  std::vector<std::pair<MapPointId, MapPointId>> fused;  // (removed, kept)
};

using CorrectionPtr = std::shared_ptr<const Correction>;

}  // namespace binloop::msg
