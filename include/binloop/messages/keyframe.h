#pragma once
// KeyFrame: tracking -> local mapping (revision 0, as tracking made it) and local mapping -> loop stages
// (revision >= 1, after local BA, with covisibility). Immutable once sent: stages pass
// std::shared_ptr<const KeyFrame>, so inside one process no copy is made, and across processes it is
// one ROS message (binloop/KeyFrame).
#include <memory>
#include <string>
#include <vector>

#include "binloop/messages/map_state.h"
#include "binloop/types/stereo_camera.h"

namespace binloop::msg {

struct KeyPoint {
  float x = 0, y = 0;  // left image, level-0 pixels
  float angle = 0;     // degrees
  uint8_t octave = 0;  // pyramid level it was detected at
  float right_x = -1;  // matched x in the right image, -1 = none
  float depth = -1;    // metres from the stereo match, -1 = none
};

struct KeyFrame {
  SlamKeyframeId id = kNoId;
  uint32_t revision = 0;
  uint64_t frame_index = 0;  // of the input sequence / bag
  double stamp_s = 0;
  StereoCamera camera;
  float scale_factor = 1.2f;  // of the pyramid the octaves refer to
  uint8_t levels = 8;
  std::vector<KeyPoint> keypoints;
  Descriptors descriptors;  // one per keypoint
  KeyframeState state;      // pose, map point per keypoint, covisibility (empty at revision 0), parent
  std::vector<MapPoint> new_points;  // the points its creator made with it (ids in point_ids)
  // Loop corrections its creator had applied when it made it (Correction::sequence). A receiver that has
  // applied more moves the pose and new points with the parent's correction (messages/correction.h).
  uint64_t corrections_seen = 0;
  // Global BA results local mapping had merged (LocalMapUpdate::merges_seen) in the map its creator tracked
  // in. A keyframe made before a merge reached tracking moves as its parent did in that merge.
  uint64_t merges_seen = 0;
  // Sent again by local mapping to a loop stage that (re)started (LocalMapper::keyframeMessages): a keyframe
  // of the map to hold and index, not a new one to search for loops with.
  bool resent = false;
};

using KeyFramePtr = std::shared_ptr<const KeyFrame>;

/// What makes `k` unusable as a keyframe in any stage, "" if nothing: a zero id, a state naming another
/// keyframe, or keypoints, descriptors and point ids that differ in number. Every stage that takes keyframes
/// (local mapping, loop closing, a state file, the ROS conversion) checks with this, and adds what only it
/// can know (ids it already holds, a message's byte counts).
std::string keyframeShapeProblem(const KeyFrame& k);

}  // namespace binloop::msg
