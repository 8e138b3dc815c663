#pragma once
// KITTI's ground truth comes from GPS/INS, and where a route passes a street twice the two passes can
// disagree in height by metres (route 02: median 1.8 m, up to 4.6 m over its loop pairs; 00 up to 1.3 m;
// 05 and 06 under 0.8 m). The renderer anchors its world in x-z but builds each object at the height of
// the pass that placed it, so such a revisit sees the street it saw before 4 m higher or lower: cars buried
// or floating, the ground drawn over the first pass's kerbs. No place recognizer can find that place.
// Levelling gives every revisiting frame the height of the earlier pass it is near and fades the change in
// and out along the path, so that each place has one height. The rendered sequence's poses.txt carries the
// levelled heights: it is that sequence's ground truth.
#include <cstddef>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop::sim {

struct LevelParams {
  double radius_m = 8;            // a frame this near (x-z) to a frame of an earlier pass revisits it...
  size_t min_frames_apart = 300;  // ... when that frame is at least this many frames earlier
  double ramp_m = 150;  // a height change fades in before and out after a revisit over this much path
};

struct LevelResult {
  std::vector<Pose3> route;   // the input with heights (y, KITTI's camera frame: down) changed
  size_t revisit_frames = 0;  // frames that took an earlier pass's height
  double max_shift_m = 0;     // the largest height change of any frame
};

/// Throws std::invalid_argument for a radius or ramp that is not positive.
LevelResult levelRevisits(const std::vector<Pose3>& route, const LevelParams& p = {});

}  // namespace binloop::sim
