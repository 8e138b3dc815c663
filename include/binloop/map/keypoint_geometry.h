#pragma once
// A keypoint and a point, for every stage that has both: the point a stereo keypoint stands for, where a
// point appears in the stereo pair, and the chi2 test local mapping (fusion, triangulation) and tracking's
// recovery apply to a point and a keypoint: the reprojection error in level-0 pixels, right-image u
// included where the keypoint has a stereo match, over the keypoint's level variance; compare with 5.991
// (mono, 2 dof) or 7.815 (stereo, 3 dof).
#include <Eigen/Core>
#include <limits>

#include "binloop/features/stereo_matcher.h"
#include "binloop/messages/keyframe.h"
#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// Matched in the right image too: the keypoint has a disparity and a depth.
inline bool hasStereo(const msg::KeyPoint& k) { return k.right_x >= 0 && k.depth > 0; }

/// The camera-frame point of a keypoint with stereo depth (k.depth > 0).
inline Eigen::Vector3d unprojectKeypoint(const msg::KeyPoint& k, const StereoCamera& cam) {
  const double z = k.depth;
  return {(k.x - cam.cx) * z / cam.fx, (k.y - cam.cy) * z / cam.fy, z};
}

/// Where a camera-frame point in front of the camera (p.z() > 0) appears: u, v in the left image and u in
/// the right one, level-0 pixels. The inverse of unprojectKeypoint.
inline Eigen::Vector3d projectStereo(const Eigen::Vector3d& p, const StereoCamera& cam) {
  const Eigen::Vector2d uv = cam.project(p);
  return {uv.x(), uv.y(), uv.x() - cam.bf() / p.z()};
}

/// The right-image x a pose optimisation or BA residual uses: the keypoint's own, or -1 (a bearing only) for
/// a keypoint that is not close (isCloseDepth) unless `p.far_disparity`. A tenth of a pixel of bias in the
/// disparity is 0.8 % of the depth of a point 30 m away: on real KITTI frames the far disparities made the
/// trajectory 0.5 % too long (docs/decisions.md). The depth itself still places new points.
inline float measuredRightX(const msg::KeyPoint& k, const StereoCamera& cam, const StereoMatchParams& p) {
  if (p.far_disparity || k.right_x < 0 || isCloseDepth(k.depth, cam, p)) return k.right_x;
  return -1.f;
}

/// Infinite, with *in_front false, for a point at or behind the camera plane.
inline double reprojectionChi2(const StereoCamera& cam, const Pose3& T_c_w, const Eigen::Vector3d& p_w,
                               const msg::KeyPoint& k, float inv_sigma2, bool* in_front) {
  const Eigen::Vector3d p = T_c_w * p_w;
  *in_front = p.z() > 0;
  if (!*in_front) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d uvr = projectStereo(p, cam);
  double e2 = (uvr.x() - k.x) * (uvr.x() - k.x) + (uvr.y() - k.y) * (uvr.y() - k.y);
  if (k.right_x >= 0) e2 += (uvr.z() - k.right_x) * (uvr.z() - k.right_x);
  return e2 * inv_sigma2;
}

}  // namespace binloop
