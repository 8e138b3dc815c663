#pragma once
// Correction: loop closing -> local mapping, after a loop was verified and the essential graph optimised.
// It carries every keyframe's pose before and after the optimisation, as loop closing knew them. Local
// mapping owns the points, so it moves them (each with its reference keyframe), moves keyframes it had
// that loop closing had not seen yet (with their spanning-tree parent), merges the points the loop
// matched, and sends tracking the result as one LocalMapUpdate. A message can thus arrive late: the receiver
// applies the change of each keyframe's pose, T_after * T_before^-1, to the pose it holds now.
#include <memory>
#include <utility>
#include <vector>

#include "binloop/messages/map_state.h"

namespace binloop::msg {

struct KeyframeCorrection {
  SlamKeyframeId id = kNoId;
  Pose3 T_w_c_before = Pose3::Identity();
  Pose3 T_w_c_after = Pose3::Identity();
};

struct Correction {
  uint64_t sequence = 0;                        // 1, 2, ... per loop closing stage
  SlamKeyframeId query = kNoId, match = kNoId;  // the loop that caused it
  std::vector<KeyframeCorrection> keyframes;
  // Points the loop's verification matched: (the query side's, the match side's). The older, match side is
  // kept. Local mapping also searches the match's neighbourhood for the query's (fuse_by_projection).
  std::vector<std::pair<MapPointId, MapPointId>> fused;
  bool fuse_by_projection = true;
};

using CorrectionPtr = std::shared_ptr<const Correction>;

}  // namespace binloop::msg
