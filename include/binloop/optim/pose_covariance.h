#pragma once
// How well a stereo frame's pose is known from the map points it matched: what odometry consumers
// (robot_localization, a pose-graph back end) need as the pose's covariance. The Gauss-Newton information
// of the frame's reprojection residuals at its pose, inverted, and scaled by the residuals' own variance
// (chi2 per degree of freedom, so a frame whose matches disagree more is trusted less). The map points
// are held exact: this is the uncertainty of tracking against the map, not the drift odometry accumulates.
#include <Eigen/Core>
#include <vector>

#include "binloop/optim/pose_optimizer.h"
#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct PoseCovariance {
  /// Of the camera centre's error in the world frame, then the rotation's about the world axes
  /// (R_w_c' = exp(dtheta) R_w_c): [x y z rx ry rz], m^2 and rad^2.
  Matrix6d covariance = Matrix6d::Zero();
  double sigma_px = 0;   // the residuals' standard deviation at octave 0 (sqrt(chi2 / dof))
  int observations = 0;  // those used
  bool valid = false;    // false: too few observations, or they do not fix the pose
};

/// The covariance of T_w_c given `inliers` (the observations the pose was optimised on, outliers left out).
PoseCovariance poseCovariance(const StereoCamera& cam, const Pose3& T_w_c,
                              const std::vector<PoseObservation>& inliers);

}  // namespace binloop
