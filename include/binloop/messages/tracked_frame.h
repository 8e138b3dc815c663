#pragma once
// TrackedFrame: tracking's result for every input frame (the runner's trajectory, the ROS odometry and
// tf). The pose is also given relative to a keyframe so that a later correction of that keyframe moves
// the frame with it (ORB-SLAM2 writes its full trajectory this way).
#include <cstdint>
#include <string>

#include "binloop/map/ids.h"
#include "binloop/types/pose.h"

namespace binloop::msg {

enum class TrackingState : uint8_t { kNotInitialized = 0, kOk = 1, kLost = 2, kRelocalized = 3 };
const char* toString(TrackingState s);

struct TrackedFrame {
  uint64_t frame_index = 0;
  double stamp_s = 0;
  TrackingState state = TrackingState::kNotInitialized;
  Pose3 T_w_c = Pose3::Identity();  // valid unless state is kNotInitialized or kLost
  SlamKeyframeId reference = kNoId;
  Pose3 T_ref_c = Pose3::Identity();    // pose relative to `reference`
  SlamKeyframeId new_keyframe = kNoId;  // set when this frame became a keyframe
  // How well T_w_c is known from the points it matched (optim/pose_covariance.h): the camera centre's
  // error in the world frame, then the rotation's about the world axes; all zero: unknown (not tracked).
  Matrix6d pose_covariance = Matrix6d::Zero();
  int features = 0, stereo_matches = 0, tracked_points = 0;
  // What the keyframe decision weighed against tracked_points: the reference keyframe's points that other
  // keyframes see too, and the keyframes waiting for local mapping (a frame that was not tracked: 0, 0;
  // localisation only, which makes no keyframe: reference_points 0).
  int reference_points = 0, mapping_queue = 0;
  // Why the frame was not tracked (bad input, lost), or that tracking started again at the motion model's
  // prediction (Tracker, restart_after_lost); empty otherwise.
  std::string problem;
  double extract_ms = 0, stereo_ms = 0, track_ms = 0;
  // Bringing tracking's copy of the map up to date with mapping's updates before this frame (in one
  // process; the ROS nodes do it between frames): a whole corrected map after a loop costs the most.
  double apply_ms = 0;
};

}  // namespace binloop::msg
