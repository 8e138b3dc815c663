#pragma once
// What the Tracking nodelet says about where the robot is: tf (map -> odom -> base -> camera, REP-105, and
// map -> slam for the SLAM's own outputs), odom with twist and covariances, and the camera's pose with its
// covariance in the slam frame (pose_with_covariance), over RobotFrames' transforms. Parameters (the
// nodelet's private ones):
//   ~map_frame (map), ~odom_frame (odom), ~base_frame (base_link), ~slam_frame (slam): frame names;
//   ~camera_in_base [x y z qx qy qz qw]: the camera's mounting; without it, the robot's TF is asked for
//     base -> camera at the first frame, and without that the camera's optical axes on a base at the camera;
//   ~publish_tf (true): false publishes no tf at all;
//   ~publish_odom_tf (true): false leaves odom -> base to the robot's own odometry and publishes map -> odom
//     computed against it (looked up in TF at each image's stamp);
//   ~ground_truth_frame: a frame that coincides with the slam frame (KITTI's ground truth), for rviz.
// While tracking is lost, map -> odom is sent again with the image's stamp, so the tree stays alive.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <optional>
#include <string>

#include "binloop_ros/robot_frames.h"

namespace binloop_ros {

struct PoseHint {
  binloop::Pose3 T_slam_cam;
  double radius_m = 5;
};

class FramePublisher {
 public:
  /// Reads the parameters above; throws ConversionError for a malformed ~camera_in_base.
  FramePublisher(ros::NodeHandle& nh, ros::NodeHandle& pnh);

  static const std::vector<std::string>& parameterNames();

  const std::string& slamFrame() const { return slam_frame_; }
  /// A tracked frame: its camera pose in the slam frame and that pose's covariance
  /// (msg::TrackedFrame::pose_covariance; zeros: unknown). `camera_frame`: the image's frame id.
  void tracked(const binloop::Pose3& T_slam_cam, const RobotFrames::Matrix6d& covariance,
               const ros::Time& stamp, const std::string& camera_frame, bool corrected);
  /// A frame that was not tracked (lost): keeps map -> odom alive.
  void lost(const ros::Time& stamp);
  /// A reset or a loaded map.
  void restart() { frames_.restart(); }
  /// The images' clock went back (a replayed or looped bag): the robot's transforms it listens to are
  /// forgotten, since tf would refuse every new one as older than what it holds (TF_OLD_DATA) for as long as
  /// the jump.
  void clockWentBack();
  /// A pose hint (/initialpose) as the camera's pose in the slam frame: a pose in map is the base's, a pose
  /// in slam the camera's. Throws ConversionError for another frame, or before the first tracked frame (the
  /// camera's mounting is not known yet).
  binloop::Pose3 hintInSlam(const std::string& frame, const binloop::Pose3& T) const;
  /// /initialpose as hintInSlam's pose and the radius to relocalise within: three standard deviations of its
  /// position (rviz sends 0.5 m), at least 5 m, as an operator clicks roughly, and at most 50 m.
  PoseHint hint(const geometry_msgs::PoseWithCovarianceStamped& m) const;
  /// The last problem (a failed TF lookup), "" if none since the last call.
  std::string takeProblem();

 private:
  void mountCamera(const std::string& camera_frame);
  void send(const binloop::Pose3& T, const ros::Time& stamp, const std::string& parent,
            const std::string& child, bool is_static = false);

  std::string map_frame_, odom_frame_, base_frame_, slam_frame_, truth_frame_;
  bool publish_tf_ = true, publish_odom_tf_ = true;
  std::optional<binloop::Pose3> mounting_param_;
  bool mounted_ = false;
  RobotFrames frames_;
  std::optional<binloop::Pose3> last_map_odom_;
  ros::Time last_robot_odom_;  // stamp of the last image the robot's odometry had a pose for
  ros::Publisher odom_pub_, pose_cov_pub_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_;
  std::vector<geometry_msgs::TransformStamped> statics_;
  std::unique_ptr<tf2_ros::Buffer> buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
  std::string problem_;
};

}  // namespace binloop_ros
