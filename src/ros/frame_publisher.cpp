#include "binloop_ros/frame_publisher.h"

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>

#include <algorithm>
#include <cmath>

#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/node_params.h"

namespace binloop_ros {

const std::vector<std::string>& FramePublisher::parameterNames() {
  static const std::vector<std::string> names = {"map_frame",       "odom_frame",        "base_frame",
                                                 "slam_frame",      "camera_in_base",    "publish_tf",
                                                 "publish_odom_tf", "ground_truth_frame"};
  return names;
}

FramePublisher::FramePublisher(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  map_frame_ = stringParam(pnh, "map_frame", "map");
  odom_frame_ = stringParam(pnh, "odom_frame", "odom");
  base_frame_ = stringParam(pnh, "base_frame", "base_link");
  slam_frame_ = stringParam(pnh, "slam_frame", "slam");
  truth_frame_ = stringParam(pnh, "ground_truth_frame", "");
  publish_tf_ = boolParam(pnh, "publish_tf", true);
  publish_odom_tf_ = boolParam(pnh, "publish_odom_tf", true);
  mounting_param_ = poseParam(pnh, "camera_in_base");
  odom_pub_ = nh.advertise<nav_msgs::Odometry>("odom", 10);
  pose_cov_pub_ = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose_with_covariance", 10);
  if (publish_tf_) {
    tf_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    static_tf_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  }
  // The robot's TF: its camera mounting, and its odometry when binloop publishes only map -> odom.
  if (!mounting_param_ || !publish_odom_tf_) {
    buffer_ = std::make_unique<tf2_ros::Buffer>();
    listener_ = std::make_unique<tf2_ros::TransformListener>(*buffer_);
  }
}

void FramePublisher::mountCamera(const std::string& camera_frame) {
  mounted_ = true;
  binloop::Pose3 T_base_cam = RobotFrames::opticalOnBase();
  bool from_tf = false;
  if (mounting_param_) {
    T_base_cam = *mounting_param_;
  } else if (buffer_) {
    try {
      T_base_cam = toPose3(
          buffer_->lookupTransform(base_frame_, camera_frame, ros::Time(0), ros::Duration(0.1)).transform);
      from_tf = true;
    } catch (const tf2::TransformException&) {  // the robot does not publish it: binloop does
    }
  }
  ROS_INFO("binloop/Tracking: camera '%s' on '%s' %s", camera_frame.c_str(), base_frame_.c_str(),
           from_tf           ? "as the robot's TF has it"
           : mounting_param_ ? "as ~camera_in_base says"
                             : "with its optical axes on the base (no ~camera_in_base, none in TF)");
  frames_ = RobotFrames(T_base_cam);
  if (!static_tf_) return;
  send(frames_.slamInMap(), ros::Time(0), map_frame_, slam_frame_, true);
  if (!from_tf) send(T_base_cam, ros::Time(0), base_frame_, camera_frame, true);
  if (!truth_frame_.empty()) send(binloop::Pose3::Identity(), ros::Time(0), slam_frame_, truth_frame_, true);
  static_tf_->sendTransform(statics_);
}

void FramePublisher::send(const binloop::Pose3& T, const ros::Time& stamp, const std::string& parent,
                          const std::string& child, bool is_static) {
  const geometry_msgs::TransformStamped t = toTransformMsg(T, stamp, parent, child);
  if (is_static) {
    statics_.push_back(t);
  } else if (tf_) {
    tf_->sendTransform(t);
  }
}

void FramePublisher::tracked(const binloop::Pose3& T_slam_cam, const RobotFrames::Matrix6d& covariance,
                             const ros::Time& stamp, const std::string& camera_frame, bool corrected) {
  if (!mounted_) mountCamera(camera_frame);
  frames_.update(T_slam_cam, covariance, stamp.toSec(), corrected);

  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = odom_frame_;
  odom.child_frame_id = base_frame_;
  odom.pose.pose = toPoseMsg(frames_.baseInOdom());
  odom.twist.twist.linear.x = frames_.linearVelocity().x();
  odom.twist.twist.linear.y = frames_.linearVelocity().y();
  odom.twist.twist.linear.z = frames_.linearVelocity().z();
  odom.twist.twist.angular.x = frames_.angularVelocity().x();
  odom.twist.twist.angular.y = frames_.angularVelocity().y();
  odom.twist.twist.angular.z = frames_.angularVelocity().z();
  odom.pose.covariance = toCovarianceMsg(frames_.poseCovariance());
  odom.twist.covariance = toCovarianceMsg(frames_.twistCovariance());
  odom_pub_.publish(odom);

  // The camera in the slam frame: TrackedFrame's covariance is already in its axes (centre, then rotation).
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = slam_frame_;
  pose.pose.pose = toPoseMsg(T_slam_cam);
  pose.pose.covariance =
      toCovarianceMsg(RobotFrames::known(covariance) ? covariance : RobotFrames::unknownCovariance());
  pose_cov_pub_.publish(pose);

  if (!tf_) return;
  if (publish_odom_tf_) {
    last_map_odom_ = frames_.odomInMap();
    send(*last_map_odom_, stamp, map_frame_, odom_frame_);
    send(frames_.baseInOdom(), stamp, odom_frame_, base_frame_);
    return;
  }
  // No waiting on the tracking callback: when the robot's odometry has not reached the image's stamp yet,
  // the last map -> odom stands, and only a second without any is a problem worth reporting.
  try {
    const binloop::Pose3 robot_T_odom_base =
        toPose3(buffer_->lookupTransform(odom_frame_, base_frame_, stamp).transform);
    last_map_odom_ = frames_.odomInMap(robot_T_odom_base);
    last_robot_odom_ = stamp;
  } catch (const tf2::TransformException& e) {
    if (!last_map_odom_ || (stamp - last_robot_odom_).toSec() > 1.0)
      problem_ = std::string("no ") + odom_frame_ + " -> " + base_frame_ +
                 " from the robot's odometry at the image's stamp (" + e.what() + "): map -> " + odom_frame_ +
                 " kept";
  }
  if (last_map_odom_) send(*last_map_odom_, stamp, map_frame_, odom_frame_);
}

binloop::Pose3 FramePublisher::hintInSlam(const std::string& frame, const binloop::Pose3& T) const {
  if (!mounted_)
    throw ConversionError("a pose hint before the first tracked frame: nothing to relocalise in yet");
  const std::string f = !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
  if (f == map_frame_) return frames_.cameraInSlam(T);
  if (f == slam_frame_) return T;
  throw ConversionError("a pose hint in frame '" + frame + "': give it in '" + map_frame_ +
                        "' (the base's pose) or '" + slam_frame_ + "' (the camera's)");
}

PoseHint FramePublisher::hint(const geometry_msgs::PoseWithCovarianceStamped& m) const {
  const double var = std::max(m.pose.covariance[0], m.pose.covariance[7]);
  return {hintInSlam(m.header.frame_id, toPose3(m.pose.pose)),
          std::clamp(3 * std::sqrt(std::max(var, 0.0)), 5.0, 50.0)};
}

void FramePublisher::clockWentBack() {
  if (buffer_) buffer_->clear();
  last_robot_odom_ = ros::Time();
}

void FramePublisher::lost(const ros::Time& stamp) {
  if (tf_ && last_map_odom_) send(*last_map_odom_, stamp, map_frame_, odom_frame_);
}

std::string FramePublisher::takeProblem() {
  std::string p;
  p.swap(problem_);
  return p;
}

}  // namespace binloop_ros
