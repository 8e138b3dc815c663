#pragma once
// A keyframe's stereo keypoint made from a 3-D point, as a rectified rig would see it: for tests and
// benchmarks that build keyframe messages without images.
#include <Eigen/Core>

#include "binloop/messages/keyframe.h"

namespace binloop::test {

/// Adds the point `p_c` (in kf's camera frame, kf.camera set) with descriptor `d` and no map point; false
/// when it is nearer than 1 m or outside the image.
inline bool addStereoKeypoint(msg::KeyFrame& kf, const Eigen::Vector3d& p_c, const Desc256& d) {
  const StereoCamera& cam = kf.camera;
  if (p_c.z() < 1) return false;
  msg::KeyPoint k;
  k.x = static_cast<float>(cam.fx * p_c.x() / p_c.z() + cam.cx);
  k.y = static_cast<float>(cam.fy * p_c.y() / p_c.z() + cam.cy);
  if (k.x < 0 || k.x >= cam.width || k.y < 0 || k.y >= cam.height) return false;
  k.depth = static_cast<float>(p_c.z());
  k.right_x = static_cast<float>(k.x - cam.bf() / p_c.z());
  kf.keypoints.push_back(k);
  kf.descriptors.push_back(d);
  kf.state.point_ids.push_back(kNoId);
  return true;
}

}  // namespace binloop::test
