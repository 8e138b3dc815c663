// RobotFrames: the SLAM's camera poses as REP-103/105 transforms (map and odom z-up, odom continuous).
#include "binloop_ros/robot_frames.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

using binloop::Pose3;
using binloop_ros::RobotFrames;

namespace {

Pose3 cameraAt(double forward_m, double yaw_left_rad = 0) {
  // In the slam frame (the first camera's optical frame): forward is +z, a left turn is about -y.
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(-yaw_left_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0, 0, forward_m);
  return T;
}

void expectNear(const Pose3& a, const Pose3& b, double tol = 1e-9) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), tol) << a.matrix() << "\nvs\n" << b.matrix();
}

}  // namespace

TEST(RobotFrames, TheMapIsZUpAndTheBaseDrivesAlongItsX) {
  RobotFrames f;  // the camera's optical axes on a base at the camera
  f.update(cameraAt(0), 0.0, false);
  expectNear(f.baseInMap(), Pose3::Identity());
  f.update(cameraAt(2, M_PI / 2), 0.5, false);
  EXPECT_NEAR(f.baseInMap().translation().x(), 2, 1e-9);
  EXPECT_NEAR(f.baseInMap().translation().y(), 0, 1e-9);
  EXPECT_NEAR(f.baseInMap().translation().z(), 0, 1e-9);
  // Turned left: the base's x now points along the map's y, its z still up.
  EXPECT_NEAR((f.baseInMap().linear() * Eigen::Vector3d::UnitX()).y(), 1, 1e-9);
  EXPECT_NEAR((f.baseInMap().linear() * Eigen::Vector3d::UnitZ()).z(), 1, 1e-9);
  EXPECT_NEAR(f.linearVelocity().x(), 4, 1e-9);       // 2 m in 0.5 s, along the base's x at the start
  EXPECT_NEAR(f.angularVelocity().z(), M_PI, 1e-9);  // 90 degrees in 0.5 s, about the base's z
  // map -> slam is the mounting: the slam frame's z (forward) is the map's x.
  EXPECT_NEAR((f.slamInMap().linear() * Eigen::Vector3d::UnitZ()).x(), 1, 1e-9);
}

TEST(RobotFrames, OdomStaysContinuousAcrossACorrectionAndMapToOdomTakesTheJump) {
  Pose3 mount = Pose3::Identity();
  mount.linear() = RobotFrames::opticalOnBase().linear();
  mount.translation() = Eigen::Vector3d(1.5, 0, 1.2);  // a camera 1.5 m ahead of the base, 1.2 m up
  RobotFrames f(mount);
  for (int i = 0; i <= 10; ++i) f.update(cameraAt(i), i * 0.1, false);
  const Pose3 odom_before = f.baseInOdom();
  expectNear(f.odomInMap() * f.baseInOdom(), f.baseInMap());
  // A loop correction moves the slam-frame pose 3 m back: odom moves by the last motion (1 m), map -> odom jumps.
  f.update(cameraAt(11 - 3), 1.1, true);
  EXPECT_NEAR((f.baseInOdom().translation() - odom_before.translation()).norm(), 1, 1e-9);
  EXPECT_NEAR(f.baseInMap().translation().x(), 8, 1e-9);
  expectNear(f.odomInMap() * f.baseInOdom(), f.baseInMap());
  // A pose hint given for the base in map is the camera's pose in slam that gives that base pose.
  expectNear(f.cameraInSlam(f.baseInMap()), cameraAt(8));
  // The robot's own odometry: map -> odom puts its base where binloop's map has it.
  Pose3 wheel = Pose3::Identity();
  wheel.translation() = Eigen::Vector3d(10.4, -0.3, 0);
  expectNear(f.odomInMap(wheel) * wheel, f.baseInMap());
}
