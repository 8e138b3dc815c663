#pragma once
// The pose of a frame that has moved far from the keyframes that measured its points: after a gap of
// 20 frames (24 m on rendered 06) the points now 10 m ahead were measured from 30-40 m, where stereo
// depth is uncertain by a metre or more. Projecting those points into the frame (the ordinary pose
// optimisation) puts that metre into every residual: the near points turn into outliers and the pose
// rests on far ones, which do not fix the distance along the road (2.4 m off, measured). What each side
// knows well is the other way round: the keyframe the direction, the frame the depth. So each match is a
// point seen twice, once by its keyframe(s) and once by the frame, each with the uncertainty of its own
// stereo, and the pose comes out of a small bundle adjustment in which the points move too and only the
// frame and the points are free.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "binloop/messages/keyframe.h"
#include "binloop/optim/local_bundle_adjustment.h"
#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// A keyframe's stereo observation of a point: where it saw it (x, y, right_x), how sure (by its level).
struct KeyframeSighting {
  uint64_t keyframe = 0;
  Pose3 T_c_w = Pose3::Identity();
  msg::KeyPoint keypoint;
  double inv_sigma2 = 1;
};

/// A frame keypoint with stereo depth matched to a map point.
struct FarMatch {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // the map point as the map has it
  std::vector<KeyframeSighting> sightings;        // at least one
  msg::KeyPoint keypoint;                         // the frame's, with right_x and depth
  double inv_sigma2 = 1;
};

struct FarPoseParams {
  int iterations = 300;  // RANSAC samples of three matches (Horn's alignment of their stereo points)
  double chi2 = 7.815;   // a match agrees when one side's stereo observation is within this (3 dof, 95 %)
  int min_inliers = 15;
  /// How far from the prior a sample's pose may be: a handful of far matches agree with poses metres
  /// away (their depth is loose on both sides), so the search stays where the prior says the camera is.
  double max_offset_m = 2;
  double max_turn_deg = 2;
};

struct FarPoseResult {
  bool ok = false;
  Pose3 T_w_c = Pose3::Identity();
  std::vector<uint8_t> inlier;  // per match, after the bundle adjustment
  int inliers = 0;
  int ransac_inliers = 0;
};

/// The frame's pose and which matches hold. A sample's pose is scored by each match's better side: the
/// frame's stereo point seen from its keyframes, or the map point seen from the frame (a far point is
/// known well by neither in depth and is judged by direction). Deterministic for a seed.
FarPoseResult farKeyframePose(const StereoCamera& cam, const std::vector<FarMatch>& matches,
                              const Pose3& prior_T_w_c, const FarPoseParams& p, uint64_t seed);

}  // namespace binloop
