#include "binloop/tracking/motion_reach.h"

#include <gtest/gtest.h>

#include "support/pose_at.h"

using namespace binloop;
using binloop::test::poseAt;

TEST(MotionReach, WithoutAPredictionEveryPoseIsAdmitted) {
  MotionReach reach;
  EXPECT_FALSE(reach.active());
  EXPECT_TRUE(reach.admits(poseAt(1e6, 0, 0)));
  EXPECT_LT(reach.nearestRefusedM(), 0);
}

TEST(MotionReach, TheRadiusGrowsWithTheSquareOfTheTimeAndTheNearestRefusalIsKept) {
  // 1 m + 1/2 * 5 m/s^2 * (2 s)^2 = 11 m around (0, 0, 10).
  MotionReach reach(Eigen::Vector3d(0, 0, 10), 1.0, 5.0, 2.0);
  EXPECT_DOUBLE_EQ(reach.radiusM(), 11.0);
  EXPECT_DOUBLE_EQ(reach.dtS(), 2.0);
  EXPECT_TRUE(reach.admits(poseAt(0, 0, 20.9)));
  EXPECT_TRUE(reach.admits(poseAt(11, 0, 10)));
  EXPECT_LT(reach.nearestRefusedM(), 0) << "nothing refused yet";
  EXPECT_FALSE(reach.admits(poseAt(0, 0, 40)));   // 30 m off
  EXPECT_FALSE(reach.admits(poseAt(0, 15, 10)));  // 15 m off
  EXPECT_FALSE(reach.admits(poseAt(0, 0, -20)));  // 30 m off again
  EXPECT_DOUBLE_EQ(reach.nearestRefusedM(), 15.0);
}
