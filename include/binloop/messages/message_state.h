#pragma once
// The stage messages' parts written to and read from a stage's state file (io/state_file.h), field by
// field. Shared by the four stages' save/load so that a keyframe or a map point is written one way only.
#include "binloop/io/state_file.h"
#include "binloop/messages/keyframe.h"

namespace binloop {

void writePose(StateWriter& w, const Pose3& T);
Pose3 readPose(StateReader& r, const char* what);
void writeCamera(StateWriter& w, const StereoCamera& c);
StereoCamera readCamera(StateReader& r);
void writeMapPoint(StateWriter& w, const msg::MapPoint& p);
msg::MapPoint readMapPoint(StateReader& r);
void writeKeyframeState(StateWriter& w, const msg::KeyframeState& s);
msg::KeyframeState readKeyframeState(StateReader& r);
void writeKeyPoints(StateWriter& w, const std::vector<msg::KeyPoint>& k);
std::vector<msg::KeyPoint> readKeyPoints(StateReader& r);
/// A whole keyframe message (keypoints, descriptors, state, new points).
void writeKeyFrame(StateWriter& w, const msg::KeyFrame& kf);
msg::KeyFrame readKeyFrame(StateReader& r);

}  // namespace binloop
