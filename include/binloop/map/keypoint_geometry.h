#pragma once
// A keypoint and a point, for every stage that has both: the point a stereo keypoint stands for, and the
// chi2 test local mapping (fusion, triangulation) and tracking's recovery apply to a point and a keypoint:
// the reprojection error in level-0 pixels, right-image u included where the keypoint has a stereo match,
// over the keypoint's level variance; compare with 5.991 (mono, 2 dof) or 7.815 (stereo, 3 dof).
#include <Eigen/Core>
#include <limits>

#include "binloop/messages/keyframe.h"
#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// The camera-frame point of a keypoint with stereo depth (k.depth > 0).
inline Eigen::Vector3d unprojectKeypoint(const msg::KeyPoint& k, const StereoCamera& cam) {
  const double z = k.depth;
  return {(k.x - cam.cx) * z / cam.fx, (k.y - cam.cy) * z / cam.fy, z};
}

/// Infinite, with *in_front false, for a point at or behind the camera plane.
inline double reprojectionChi2(const StereoCamera& cam, const Pose3& T_c_w, const Eigen::Vector3d& p_w,
                               const msg::KeyPoint& k, float inv_sigma2, bool* in_front) {
  const Eigen::Vector3d p = T_c_w * p_w;
  *in_front = p.z() > 0;
  if (!*in_front) return std::numeric_limits<double>::infinity();
  const double u = cam.fx * p.x() / p.z() + cam.cx, v = cam.fy * p.y() / p.z() + cam.cy;
  double e2 = (u - k.x) * (u - k.x) + (v - k.y) * (v - k.y);
  if (k.right_x >= 0) {
    const double ur = u - cam.bf() / p.z();
    e2 += (ur - k.right_x) * (ur - k.right_x);
  }
  return e2 * inv_sigma2;
}

}  // namespace binloop
