#include "binloop_ros/robot_frames.h"

#include <Eigen/Geometry>

namespace binloop_ros {

RobotFrames::RobotFrames(const binloop::Pose3& T_base_cam) : T_base_cam_(T_base_cam), T_cam_base_(T_base_cam.inverse()) {}

binloop::Pose3 RobotFrames::opticalOnBase() {
  binloop::Pose3 T = binloop::Pose3::Identity();
  // Columns: the camera's x (right), y (down), z (forward) in the base's axes.
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return T;
}

void RobotFrames::update(const binloop::Pose3& T_slam_cam, double stamp_s, bool corrected) {
  // T_map_base = T_map_slam * T_slam_cam * T_cam_base, with T_map_slam = T_base_cam.
  const binloop::Pose3 T_map_base(T_base_cam_ * T_slam_cam * T_cam_base_);
  if (have_last_) {
    const binloop::Pose3 motion = corrected ? last_motion_ : binloop::Pose3(T_map_base_.inverse() * T_map_base);
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
