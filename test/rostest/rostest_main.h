#pragma once
// The main() of a rostest node: gtest over a running ROS node whose callbacks a background spinner serves.
#include <gtest/gtest.h>
#include <ros/ros.h>

namespace binloop::test {

inline int runRostest(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return rc;
}

}  // namespace binloop::test
