#pragma once
// How much tilt each sharp turn leaves in an estimated trajectory. A stereo tracker's pose wobbles about the
// horizontal axes in a fast turn; whatever of it stays in the map after the turn, the next straight turns
// into height error. Comparing this turn by turn with a peer's trajectory on the same route shows where a
// drift starts, which a whole-trajectory ATE cannot.
#include <cstddef>
#include <vector>

#include "binloop/eval/trajectory_metrics.h"
#include "binloop/types/pose.h"

namespace binloop {

struct SharpTurn {
  int first = 0, last = 0;  // ground-truth frames, inclusive
};

struct SharpTurnParams {
  double start_deg_per_frame = 1.5;  // a turn starts where the truth turns faster than this...
  double keep_deg_per_frame = 0.8;   // ... and lasts while it turns faster than this
  int min_frames = 8;                // shorter ones are not counted
  int pad_frames = 5;                // frames added on either side, so that the wobble has settled
};

/// The sharp turns of a ground-truth trajectory (camera-to-world poses, one per frame), in order; turns
/// that follow each other closely may share frames.
std::vector<SharpTurn> sharpTurns(const std::vector<Pose3>& truth, const SharpTurnParams& p = {});

struct TurnTilt {
  SharpTurn turn;
  double tilt_deg = 0;
};

/// For each turn whose first and last frames both have an estimate: the error of the estimate's rotation
/// from the turn's first frame to its last, about the ground truth world's two horizontal axes, in degrees.
/// That world is the first camera's, as in KITTI: x right, y down (the vertical, taken out), z forward. The
/// estimate's world does not matter (a run started mid-route is measured as one started at frame 0).
std::vector<TurnTilt> tiltLeftByTurns(const MatchedPoses& m, const std::vector<SharpTurn>& turns);

}  // namespace binloop
