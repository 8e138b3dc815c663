#pragma once
// New map points from two keyframes (ORB-SLAM2's CreateNewMapPoints, the geometry half): a keypoint seen
// in both, with or without stereo depth, becomes a 3-D point when the rays meet at a usable angle, or
// when one view's stereo depth is the better estimate. The matching half is epipolar_matcher.h.
#include <Eigen/Core>
#include <optional>

#include "binloop/map/scale_pyramid.h"
#include "binloop/messages/keyframe.h"
#include "binloop/types/pose.h"

namespace binloop {

/// The linear (DLT) triangulation of one point from two views: x_i are normalised image coordinates
/// ((u - cx) / fx, (v - cy) / fy) in cameras with poses T_ci_w. The point X (homogeneous) solves
///   [x1 P1_3 - P1_1; y1 P1_3 - P1_2; x2 P2_3 - P2_1; y2 P2_3 - P2_2] X = 0
/// (P_k the k-th row of [R|t]) in the least-squares sense: the right singular vector of the smallest
/// singular value. Empty when that vector is at infinity (w ~ 0).
std::optional<Eigen::Vector3d> triangulateLinear(const Pose3& T_c1_w, const Pose3& T_c2_w,
                                                 const Eigen::Vector2d& x1, const Eigen::Vector2d& x2);

struct TriangulationParams {
  /// Rays closer than this to parallel (cos of the angle between them) are not triangulated from two
  /// views: 0.9998 is about 1.1 degrees (ORB-SLAM2's threshold for monocular rays).
  double max_ray_cos = 0.9998;
  double chi2_mono = 5.991;        // 2 dof, 95 %: the reprojection test of a keypoint without stereo
  double chi2_stereo = 7.815;      // 3 dof, 95 %: with its right-image x as well
  double scale_ratio_slack = 1.5;  // distance ratio vs pyramid-level ratio (ORB-SLAM2's ratioFactor)
};

/// One view of a candidate point: the keyframe's pose, camera and the keypoint.
struct TriangulationView {
  const Pose3* T_w_c;
  const StereoCamera* camera;
  const msg::KeyPoint* keypoint;
};

/// Why a match did not become a point (counted in the local-mapping statistics).
enum class TriangulationResult { kOk, kParallel, kBehind, kReprojection, kScale };

/// The point that a keypoint seen in two keyframes gives, as ORB-SLAM2 decides it: two-view triangulation
/// when the rays' angle is larger than both views' stereo angle (and than max_ray_cos unless a view has
/// stereo), else the stereo point of the view with the wider stereo angle; then it must lie in front of
/// both, reproject within chi2 in both (stereo residual included where there is one), and its distance
/// ratio must agree with the octave ratio. `p_w` is set only for kOk.
TriangulationResult triangulatePair(const TriangulationView& a, const TriangulationView& b,
                                    const ScalePyramid& s, const TriangulationParams& p,
                                    Eigen::Vector3d* p_w);

}  // namespace binloop
