#include "binloop/messages/keyframe.h"

namespace binloop::msg {

std::string keyframeShapeProblem(const KeyFrame& k) {
  if (k.id == kNoId) return "a keyframe without an id";
  if (k.state.id != k.id)
    return "keyframe " + std::to_string(k.id) + ": its state names keyframe " + std::to_string(k.state.id);
  if (k.descriptors.size() != k.keypoints.size() || k.state.point_ids.size() != k.keypoints.size()) {
    return "keyframe " + std::to_string(k.id) + ": " + std::to_string(k.keypoints.size()) +
           " keypoints but " + std::to_string(k.descriptors.size()) + " descriptors and " +
           std::to_string(k.state.point_ids.size()) + " point ids";
  }
  return "";
}

}  // namespace binloop::msg
