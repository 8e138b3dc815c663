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
  EXPECT_NEAR(f.linearVelocity().x(), 4, 1e-9);      // 2 m in 0.5 s, along the base's x at the start
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
  // A loop correction moves the slam-frame pose 3 m back: odom moves by the last motion (1 m), map -> odom
  // jumps.
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

namespace {

// The camera moved by (dc, dtheta) in the slam frame: centre c + dc, rotation exp(dtheta) R.
Pose3 moved(const Pose3& T_slam_cam, const Eigen::Matrix<double, 6, 1>& d) {
  Pose3 T = T_slam_cam;
  const Eigen::Vector3d w = d.tail<3>();
  T.linear() = (Eigen::AngleAxisd(w.norm(), w.normalized()) * T_slam_cam.linear()).eval();
  T.translation() += d.head<3>();
  return T;
}

}  // namespace

// The odometry's covariance is the camera pose's, carried to the base in odom: checked against what a small
// move of the camera does to baseInOdom(), on a camera mounted off the base's origin and turned.
TEST(RobotFrames, PoseCovarianceIsTheCamerasCarriedToTheBaseInOdom) {
  Pose3 mount = RobotFrames::opticalOnBase();
  mount.linear() = (Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) * mount.linear()).eval();
  mount.translation() = Eigen::Vector3d(1.5, 0.3, 1.2);  // camera 1.5 m ahead of the base, 1.2 m up
  const Pose3 first = cameraAt(0), second = cameraAt(1.0, 0.3);
  Eigen::Matrix<double, 6, 1> d;
  d << 2e-6, -1e-6, 3e-6, 1e-6, -2e-6, 1.5e-6;
  RobotFrames a(mount), b(mount);
  a.update(first, 0.0, false);
  b.update(first, 0.0, false);
  a.update(second, 0.1, false);
  b.update(moved(second, d), 0.1, false);
  // The base's error in odom: position, then rotation about odom's axes.
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = b.baseInOdom().translation() - a.baseInOdom().translation();
  const Eigen::AngleAxisd aa(b.baseInOdom().linear() * a.baseInOdom().linear().transpose());
  e.tail<3>() = aa.angle() * aa.axis();

  RobotFrames c(mount);
  c.update(first, RobotFrames::Matrix6d::Zero(), 0.0, false);
  EXPECT_EQ(c.poseCovariance()(0, 0), RobotFrames::kUnknown) << "zeros: unknown";
  c.update(second, d * d.transpose(), 0.1, false);
  const RobotFrames::Matrix6d expected = e * e.transpose();
  EXPECT_LT((c.poseCovariance() - expected).cwiseAbs().maxCoeff(), 1e-3 * expected.cwiseAbs().maxCoeff())
      << c.poseCovariance() << "\nvs\n"
      << expected;
  EXPECT_EQ(c.twistCovariance()(0, 0), RobotFrames::kUnknown) << "the last pose's covariance was unknown";
}

TEST(RobotFrames, TwistCovarianceIsTheTwoPosesErrorsOverTheStep) {
  RobotFrames f;  // camera on the base's origin, optical axes
  RobotFrames::Matrix6d cov = RobotFrames::Matrix6d::Zero();
  cov.diagonal() << 1e-4, 4e-4, 9e-4, 1e-6, 4e-6, 9e-6;  // slam axes: x right, y down, z forward
  f.update(cameraAt(0), cov, 0.0, false);
  f.update(cameraAt(1.0), cov, 0.1, false);
  // The base's x is the camera's z: twice 9e-4 m^2 over (0.1 s)^2.
  EXPECT_NEAR(f.twistCovariance()(0, 0), 2 * 9e-4 / 0.01, 1e-9);
  EXPECT_NEAR(f.twistCovariance()(1, 1), 2 * 1e-4 / 0.01, 1e-9);
  EXPECT_NEAR(f.twistCovariance()(5, 5), 2 * 4e-6 / 0.01, 1e-9);  // yaw: about the camera's y
  EXPECT_NEAR(f.poseCovariance()(2, 2), 4e-4, 1e-12);             // odom's z is the camera's -y
  f.update(cameraAt(5.0), cov, 0.2, true);
  EXPECT_EQ(f.twistCovariance()(0, 0), RobotFrames::kUnknown)
      << "across a correction the step is not measured";
}
