// StampGate: which stereo pairs' stamps tracking takes (include/binloop_ros/stamp_gate.h).
#include "binloop_ros/stamp_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

using binloop_ros::StampGate;
using V = StampGate::Verdict;

TEST(StampGate, AStampOutsideRosRangeIsDroppedAndTheClockGoesOn) {
  StampGate g;
  EXPECT_EQ(g.check(100.0).verdict, V::kTake);
  for (double bad : {4294967295.9, double(NAN), double(INFINITY), -1.0, 0.0}) {
    const auto d = g.check(bad);
    EXPECT_EQ(d.verdict, V::kDrop) << bad;
    EXPECT_NE(d.reason.find("outside ROS's time range"), std::string::npos) << d.reason;
  }
  EXPECT_EQ(g.check(100.1).verdict, V::kTake);
}

// One pair a million seconds ahead is an outlier: dropped, and the pairs after it are taken as before.
TEST(StampGate, OneStampFarAheadIsDroppedNotAdopted) {
  StampGate g;
  for (int i = 0; i < 10; ++i) ASSERT_EQ(g.check(100 + 0.1 * i).verdict, V::kTake);
  const auto d = g.check(1e6);
  EXPECT_EQ(d.verdict, V::kDrop);
  EXPECT_NE(d.reason.find("more than ~max_time_jump"), std::string::npos) << d.reason;
  for (int i = 10; i < 20; ++i) EXPECT_EQ(g.check(100 + 0.1 * i).verdict, V::kTake) << i;
}

// The same pairs sent again (rosbag play -l, a second bag): after three that agree, the clock restarted.
TEST(StampGate, TheClockStartingAgainIsTakenAfterThreePairs) {
  StampGate g;
  for (int i = 0; i < 80; ++i) ASSERT_EQ(g.check(100 + 0.2 * i).verdict, V::kTake);
  EXPECT_EQ(g.check(100.0).verdict, V::kDrop);
  EXPECT_EQ(g.check(100.2).verdict, V::kDrop);
  const auto d = g.check(100.4);
  EXPECT_EQ(d.verdict, V::kRestart);
  EXPECT_NE(d.reason.find("went back"), std::string::npos) << d.reason;
  EXPECT_EQ(g.check(100.6).verdict, V::kTake);
  // A late pair (one frame back) is dropped, not a restart.
  EXPECT_EQ(g.check(100.4).verdict, V::kDrop);
  EXPECT_EQ(g.check(100.8).verdict, V::kTake);
}

// A camera whose clock really jumps (a pause of a minute) is followed once pairs agree on the new time.
TEST(StampGate, AForwardJumpThatPersistsIsTaken) {
  StampGate g({5, 3});
  ASSERT_EQ(g.check(10).verdict, V::kTake);
  EXPECT_EQ(g.check(70).verdict, V::kDrop);
  EXPECT_EQ(g.check(70.1).verdict, V::kDrop);
  EXPECT_EQ(g.check(70.2).verdict, V::kJumpedForward);
  EXPECT_EQ(g.check(70.3).verdict, V::kTake);
  EXPECT_EQ(g.check(70.3).verdict, V::kDrop);  // repeated
  // Outliers that do not agree with each other never make a run.
  for (double t : {1e5, 2e5, 3e5, 4e5}) EXPECT_EQ(g.check(t).verdict, V::kDrop) << t;
  EXPECT_EQ(g.check(70.4).verdict, V::kTake);
}

TEST(StampGate, AfterAResetAnyStampIsTaken) {
  StampGate g;
  ASSERT_EQ(g.check(500).verdict, V::kTake);
  g.reset();
  EXPECT_EQ(g.check(3).verdict, V::kTake);
  EXPECT_THROW(StampGate({0, 3}), std::invalid_argument);
  EXPECT_THROW(StampGate({5, 0}), std::invalid_argument);
}
