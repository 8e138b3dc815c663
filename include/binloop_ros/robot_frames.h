#pragma once
// The tracker's poses in a robot's frames (REP-103, REP-105), as plain transforms; the Tracking nodelet
// publishes them. The SLAM works in its own frame, `slam`: the optical frame of the camera at the map's first
// frame (z forward, y down). The robot's `map` and `odom` are z-up like its base (x forward, y left, z up);
// the base carries the camera at T_base_cam (from the robot's TF, a parameter, or by default the camera's
// optical axes on a base at the camera). `map` is where the base was when the SLAM's map began, so
// T_map_slam = T_base_cam. `odom` is continuous: it integrates the base's frame-to-frame motion, except
// across a loop correction, where the SLAM's pose jumps: there the previous motion is repeated and map ->
// odom takes the jump.
#include <Eigen/Core>

#include "binloop/types/pose.h"

namespace binloop_ros {

class RobotFrames {
 public:
  using Matrix6d = binloop::Matrix6d;

  explicit RobotFrames(const binloop::Pose3& T_base_cam = opticalOnBase());

  /// The camera's optical axes on a z-up, x-forward base at the same place: x forward = the camera's z,
  /// y left = -x, z up = -y.
  static binloop::Pose3 opticalOnBase();

  /// A tracked frame's camera pose in the slam frame at `stamp_s`; `corrected`: a loop correction (or a new
  /// map) moved the slam-frame poses since the last call.
  void update(const binloop::Pose3& T_slam_cam, double stamp_s, bool corrected);
  /// The same, with the pose's covariance (msg::TrackedFrame::pose_covariance: the camera centre's and
  /// rotation's errors in the slam frame; all zero: unknown).
  void update(const binloop::Pose3& T_slam_cam, const Matrix6d& cov_slam_cam, double stamp_s, bool corrected);
  /// Forget the motion (a reset or a loaded map); odom goes on from where it is.
  void restart() { have_last_ = false; }
  bool started() const { return started_; }

  const binloop::Pose3& baseInCamera() const { return T_cam_base_; }
  const binloop::Pose3& cameraInBase() const { return T_base_cam_; }
  /// Where the camera is in the slam frame when the base is at T_map_base (a pose given in map).
  binloop::Pose3 cameraInSlam(const binloop::Pose3& T_map_base) const {
    return binloop::Pose3(T_cam_base_ * T_map_base *
                          T_base_cam_);  // T_slam_map = T_cam_base (map -> slam = mounting)
  }
  /// The static map -> slam transform.
  binloop::Pose3 slamInMap() const { return T_base_cam_; }
  binloop::Pose3 baseInMap() const { return T_map_base_; }
  /// binloop's own odometry: T_odom_base.
  binloop::Pose3 baseInOdom() const { return T_odom_base_; }
  /// map -> odom for binloop's own odometry.
  binloop::Pose3 odomInMap() const { return binloop::Pose3(T_map_base_ * T_odom_base_.inverse()); }
  /// map -> odom when the robot's own odometry publishes odom -> base (T_odom_base, at the same stamp).
  binloop::Pose3 odomInMap(const binloop::Pose3& robot_T_odom_base) const {
    return binloop::Pose3(T_map_base_ * robot_T_odom_base.inverse());
  }
  /// The base's velocity in its own frame over the last step (m/s, rad/s); zero before two frames.
  const Eigen::Vector3d& linearVelocity() const { return v_; }
  const Eigen::Vector3d& angularVelocity() const { return w_; }
  /// The covariance of baseInOdom() (nav_msgs/Odometry's pose: the base's position error in odom, then its
  /// rotation error about odom's axes), from the last pose's covariance; kUnknown's diagonal when unknown.
  const Matrix6d& poseCovariance() const { return pose_cov_; }
  /// The covariance of the velocities (in the base frame, as Odometry's twist): the last two poses'
  /// errors, taken as independent, over the step's time. kUnknown's diagonal before two known poses.
  const Matrix6d& twistCovariance() const { return twist_cov_; }
  /// The variance that stands for "unknown" (m^2, rad^2): large enough that a filter ignores the value.
  static constexpr double kUnknown = 1e6;
  /// Whether a TrackedFrame's pose covariance is known (all zero: unknown).
  static bool known(const Matrix6d& cov) { return !cov.isZero(0) && cov.allFinite(); }
  static Matrix6d unknownCovariance() { return kUnknown * Matrix6d::Identity(); }

 private:
  binloop::Pose3 T_base_cam_, T_cam_base_;
  binloop::Pose3 T_map_base_ = binloop::Pose3::Identity(), T_odom_base_ = binloop::Pose3::Identity();
  binloop::Pose3 last_motion_ = binloop::Pose3::Identity();  // base frame-to-frame
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero(), w_ = Eigen::Vector3d::Zero();
  Matrix6d pose_cov_ = unknownCovariance(), twist_cov_ = unknownCovariance();
  bool pose_cov_known_ = false;
  double last_stamp_s_ = 0;
  bool have_last_ = false, started_ = false;
};

}  // namespace binloop_ros
