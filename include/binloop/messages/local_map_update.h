#pragma once
// LocalMapUpdate: local mapping -> tracking, after each keyframe it processed (insertion, culling,
// triangulation, fusion, local BA). A delta: entries not named are unchanged. Tracking applies it to its own
// copy of the local map; `keyframes` and `points` overwrite what tracking holds for those ids.
#include <utility>
#include <vector>

#include "binloop/messages/map_state.h"

namespace binloop::msg {

struct LocalMapUpdate {
  uint64_t sequence = 0;                 // 1, 2, ... per mapper
  SlamKeyframeId keyframe = kNoId;       // the keyframe whose processing produced it
  std::vector<KeyframeState> keyframes;  // inserted or refined
  std::vector<MapPoint> points;          // created, moved by BA, or whose descriptor/range changed
  std::vector<std::pair<MapPointId, MapPointId>> fused;  // (removed, kept): the same point seen twice
  std::vector<MapPointId> culled_points;
  std::vector<SlamKeyframeId> culled_keyframes;
  uint64_t corrections_seen = 0;  // loop corrections applied before it was made (Correction::sequence)
  // Global BA results merged before it was made, counted by the mapper that sent it (not saved with a map:
  // a loaded or resumed mapper counts from 0 again, and tracking follows its count).
  uint64_t merges_seen = 0;
  bool correction = false;  // the whole map after a loop correction or a global BA, not one keyframe's
  bool whole_map = false;   // the whole map sent again to a stage that (re)started (LocalMapper::wholeMap)
  // With whole_map: the highest counters of tracking's keyframe and point ids the map holds or still refers
  // to (culled keyframes, fused points), so that a restarted tracker issues none of them again.
  uint64_t tracking_keyframe_ids = 0, tracking_point_ids = 0;
  // what it cost, for timing.csv and the ROS diagnostics
  double total_ms = 0, ba_ms = 0, triangulation_ms = 0;
  int ba_iterations = 0;
  int ba_outliers = 0;
  int points_triangulated = 0;       // created by two-view triangulation with covisible keyframes
  int points_fused_across_loop = 0;  // a correction's merges
};

using LocalMapUpdatePtr = std::shared_ptr<const LocalMapUpdate>;

}  // namespace binloop::msg
