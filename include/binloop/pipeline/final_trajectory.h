#pragma once
// What run and record-run write as trajectory.kitti.txt / .tum.txt: every frame's final pose, riding on its
// reference keyframe as local mapping left it, so that loop corrections and BA reach the frames between
// keyframes too.
#include <functional>
#include <string>
#include <vector>

#include "binloop/messages/tracked_frame.h"
#include "binloop/types/pose.h"

namespace binloop {

/// The pose of a keyframe, false when it is not (or no longer) known.
using KeyframePoseFn = std::function<bool(SlamKeyframeId, Pose3*)>;

/// A lost frame, or one whose reference keyframe is unknown, keeps the pose tracking gave it.
Trajectory finalTrajectory(const std::vector<msg::TrackedFrame>& frames, const KeyframePoseFn& keyframe_pose);

/// `<stem>.kitti.txt` (poses only) and `<stem>.tum.txt` (with stamps).
void writeTrajectoryFiles(const std::string& stem, const Trajectory& t);

}  // namespace binloop
