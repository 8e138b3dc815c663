// Runs under rostest beside kitti_stereo.launch started as a robot would start it (robot_frames.test): the
// robot's URDF gives base_link -> camera through robot_state_publisher, the robot's wheel odometry (this
// node) publishes odom -> base_link, and binloop runs with publish_odom_tf:=false.
// This node plays the rendered drive with a wheel odometry that drifts (2 % long, 0.03 degrees a frame to the
// left) and checks the tree (map -> odom -> base_link -> camera, each edge from one publisher) and that
// binloop's map -> odom puts the base where it is after the loop, though the wheels put it metres away.
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Geometry>
#include <map>
#include <mutex>

#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/topics.h"
#include "rendered_drive.h"
#include "rostest_main.h"

namespace {

namespace topics = binloop_ros::topics;
using binloop::Pose3;

// The camera on the robot, as robot.urdf mounts it: 1.2 m ahead of base_link and 1.6 m up, optical axes
// (z forward, y down).
Pose3 cameraInBase() {
  Pose3 T = Pose3::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T.translation() = Eigen::Vector3d(1.2, 0, 1.6);
  return T;
}

}  // namespace

TEST(RobotFrames, MapToOdomAgainstDriftingWheelOdometryPutsTheBaseWhereItIs) {
  const binloop::test::Drive& d = binloop::test::drive();
  ASSERT_TRUE(d.problem.empty()) << d.problem;
  const auto pairs = binloop::test::readPairs(d.bag);
  ASSERT_EQ(pairs.size(), d.route.size());

  ros::NodeHandle nh;
  std::mutex m;
  std::set<double> poses;
  std::map<std::string, size_t> sent;  // "parent -> child": how many transforms of it arrived
  auto sub_pose = nh.subscribe<geometry_msgs::PoseStamped>("/binloop/pose", 1000, [&](const auto& p) {
    std::lock_guard<std::mutex> lk(m);
    poses.insert(p->header.stamp.toSec());
  });
  auto onTf = [&](const tf2_msgs::TFMessage::ConstPtr& msg) {
    std::lock_guard<std::mutex> lk(m);
    for (const auto& t : msg->transforms) ++sent[t.header.frame_id + " -> " + t.child_frame_id];
  };
  auto sub_tf = nh.subscribe<tf2_msgs::TFMessage>("/tf", 1000, onTf);
  auto sub_static = nh.subscribe<tf2_msgs::TFMessage>("/tf_static", 100, onTf);
  tf2_ros::Buffer buffer(ros::Duration(600));
  tf2_ros::TransformListener listener(buffer);
  tf2_ros::TransformBroadcaster wheels;
  ros::Publisher left = nh.advertise<sensor_msgs::Image>(topics::kLeftImage, 10);
  ros::Publisher right = nh.advertise<sensor_msgs::Image>(topics::kRightImage, 10);
  ros::Publisher left_info = nh.advertise<sensor_msgs::CameraInfo>(topics::kLeftInfo, 10);
  ros::Publisher right_info = nh.advertise<sensor_msgs::CameraInfo>(topics::kRightInfo, 10);
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(60);
  while (left.getNumSubscribers() == 0 && ros::WallTime::now() < until) ros::WallDuration(0.01).sleep();
  ASSERT_GT(left.getNumSubscribers(), 0u) << "the Tracking nodelet never subscribed";
  ros::WallDuration(1.0).sleep();  // robot_state_publisher's transform reaches binloop's listener

  // Ground truth: the base's pose in a z-up frame at its first pose (what binloop's map is).
  const Pose3 M = cameraInBase();
  auto truth = [&](size_t i) { return Pose3(M * d.route.front().inverse() * d.route[i] * M.inverse()); };
  Pose3 wheel = Pose3::Identity();
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (i > 0) {
      Pose3 step = truth(i - 1).inverse() * truth(i);
      step.translation() *= 1.02;
      step.linear() = Eigen::AngleAxisd(0.0005, Eigen::Vector3d::UnitZ()).toRotationMatrix() * step.linear();
      wheel = wheel * step;
    }
    const ros::Time stamp = pairs[i].left.header.stamp;
    wheels.sendTransform(binloop_ros::toTransformMsg(wheel, stamp, "odom", "base_link"));
    left_info.publish(pairs[i].left_info);
    right_info.publish(pairs[i].right_info);
    left.publish(pairs[i].left);
    right.publish(pairs[i].right);
    // Paced by the graph: the next pair goes when this one's pose is out (or after a second).
    const ros::WallTime wait = ros::WallTime::now() + ros::WallDuration(1.0);
    while (ros::WallTime::now() < wait) {
      {
        std::lock_guard<std::mutex> lk(m);
        if (poses.count(stamp.toSec())) break;
      }
      ros::WallDuration(0.005).sleep();
    }
  }
  ros::WallDuration(2.0).sleep();  // the last transforms arrive

  const ros::Time last = pairs.back().left.header.stamp;
  std::string parent;
  ASSERT_TRUE(buffer._getParent("base_link", last, parent));
  EXPECT_EQ(parent, "odom");
  ASSERT_TRUE(buffer._getParent("odom", last, parent));
  EXPECT_EQ(parent, "map");
  ASSERT_TRUE(buffer._getParent("slam", last, parent));
  EXPECT_EQ(parent, "map");
  ASSERT_TRUE(buffer._getParent(topics::kLeftFrame, last, parent));
  EXPECT_EQ(parent, "base_link");
  {
    std::lock_guard<std::mutex> lk(m);
    // One publisher an edge: as many odom -> base_link as the wheels sent, the mounting once (the URDF's).
    EXPECT_EQ(sent["odom -> base_link"], pairs.size()) << "binloop published odom -> base_link too";
    EXPECT_EQ(sent[std::string("base_link -> ") + topics::kLeftFrame], 1u)
        << "binloop published the camera's mounting though the robot's TF has it";
    EXPECT_GT(sent["map -> odom"], pairs.size() * 9 / 10);
  }
  const Pose3 T_map_base = binloop_ros::toPose3(buffer.lookupTransform("map", "base_link", last).transform);
  const double wheel_err = (wheel.translation() - truth(pairs.size() - 1).translation()).norm();
  const double err = (T_map_base.translation() - truth(pairs.size() - 1).translation()).norm();
  // In the test's XML result (rostest keeps no stdout of a test node).
  ::testing::Test::RecordProperty("wheel_odometry_error_m", std::to_string(wheel_err));
  ::testing::Test::RecordProperty("map_base_error_m", std::to_string(err));
  EXPECT_GT(wheel_err, 2.0) << "the wheels do not drift enough for the test to mean anything";
  EXPECT_LT(err, 0.6);
  // z up: the base stays level in map.
  EXPECT_GT((T_map_base.linear() * Eigen::Vector3d::UnitZ()).z(), 0.99);
}

int main(int argc, char** argv) { return binloop::test::runRostest(argc, argv, "robot_frames_rostest"); }
