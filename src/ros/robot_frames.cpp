#include "binloop_ros/robot_frames.h"

#include <Eigen/Geometry>

namespace binloop_ros {

RobotFrames::RobotFrames(const binloop::Pose3& T_base_cam)
    : T_base_cam_(T_base_cam), T_cam_base_(T_base_cam.inverse()) {}

binloop::Pose3 RobotFrames::opticalOnBase() {
  binloop::Pose3 T = binloop::Pose3::Identity();
  // Columns: the camera's x (right), y (down), z (forward) in the base's axes.
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return T;
}

void RobotFrames::update(const binloop::Pose3& T_slam_cam, const Matrix6d& cov_slam_cam, double stamp_s,
                         bool corrected) {
  const bool had_last = have_last_;
  const double dt = stamp_s - last_stamp_s_;
  update(T_slam_cam, stamp_s, corrected);
  const Matrix6d last_cov = pose_cov_;
  const bool last_known = pose_cov_known_;
  pose_cov_known_ = known(cov_slam_cam);
  if (!pose_cov_known_) {
    pose_cov_ = twist_cov_ = unknownCovariance();
    return;
  }
  // The camera's errors in slam (dc, dtheta) are the base's in odom after a change of axes, R_odom_slam, and
  // the lever from the camera to the base: the base at c + R_odom_cam t_cam_base moves by dtheta x that
  // lever.
  const Eigen::Matrix3d R_odom_cam = T_odom_base_.linear() * T_base_cam_.linear();
  const Eigen::Matrix3d R_odom_slam = R_odom_cam * T_slam_cam.linear().transpose();
  const Eigen::Vector3d lever = R_odom_cam * T_cam_base_.translation();
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = R_odom_slam;
  J.topRightCorner<3, 3>() = -binloop::skew(lever) * R_odom_slam;
  J.bottomRightCorner<3, 3>() = R_odom_slam;
  pose_cov_ = J * cov_slam_cam * J.transpose();
  if (!had_last || !last_known || corrected || dt <= 1e-6) {
    twist_cov_ = unknownCovariance();
    return;
  }
  Matrix6d R = Matrix6d::Zero();  // odom axes -> the base's, for both halves
  R.topLeftCorner<3, 3>() = R.bottomRightCorner<3, 3>() = T_odom_base_.linear().transpose();
  twist_cov_ = R * (pose_cov_ + last_cov) * R.transpose() / (dt * dt);
}

void RobotFrames::update(const binloop::Pose3& T_slam_cam, double stamp_s, bool corrected) {
  // T_map_base = T_map_slam * T_slam_cam * T_cam_base, with T_map_slam = T_base_cam.
  const binloop::Pose3 T_map_base(T_base_cam_ * T_slam_cam * T_cam_base_);
  if (have_last_) {
    const binloop::Pose3 motion =
        corrected ? last_motion_ : binloop::Pose3(T_map_base_.inverse() * T_map_base);
    T_odom_base_ = T_odom_base_ * motion;
    const double dt = stamp_s - last_stamp_s_;
    if (dt > 1e-6) {
      v_ = motion.translation() / dt;
      const Eigen::AngleAxisd aa(motion.linear());
      w_ = aa.axis() * aa.angle() / dt;
    }
    last_motion_ = motion;
  } else if (!started_) {
    T_odom_base_ = T_map_base;  // odom starts where map does: at the base's first pose
  }
  T_map_base_ = T_map_base;
  last_stamp_s_ = stamp_s;
  have_last_ = started_ = true;
}

}  // namespace binloop_ros
