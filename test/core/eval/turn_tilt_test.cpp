#include "binloop/eval/turn_tilt.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace binloop;

namespace {

Eigen::Matrix3d about(const Eigen::Vector3d& axis, double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

// 40 frames straight ahead, a right turn of 90 degrees at 3 degrees a frame (frames 40-70), 40 frames
// straight; climbing, 0.1 degrees a frame (so that a camera's axes are not the world's in the turn).
std::vector<Pose3> routeWithOneTurn() {
  std::vector<Pose3> poses;
  Pose3 T = Pose3::Identity();
  for (int i = 0; i < 110; ++i) {
    poses.push_back(T);
    const double yaw = i >= 40 && i < 70 ? 3.0 : 0.0;
    Pose3 step = Pose3::Identity();
    step.linear() = about(Eigen::Vector3d::UnitY(), yaw) * about(Eigen::Vector3d::UnitX(), -0.1);
    step.translation() = Eigen::Vector3d(0, 0, 1);
    T = T * step;
  }
  return poses;
}

MatchedPoses matched(const std::vector<Pose3>& gt, const std::vector<Pose3>& est) {
  MatchedPoses m;
  for (size_t i = 0; i < gt.size(); ++i) {
    m.frames.push_back(static_cast<int>(i));
    m.gt.push_back(gt[i]);
    m.est.push_back(est[i]);
  }
  m.gt_frames = gt.size();
  return m;
}

}  // namespace

TEST(TurnTilt, FindsTheTurnWithItsMarginsAndNothingOnTheStraights) {
  const auto turns = sharpTurns(routeWithOneTurn());
  ASSERT_EQ(turns.size(), 1u);
  EXPECT_EQ(turns[0].first, 35);  // the truth turns between frames 40 and 70; 5 frames either side
  EXPECT_EQ(turns[0].last, 75);
  SharpTurnParams longer;
  longer.min_frames = 40;
  EXPECT_TRUE(sharpTurns(routeWithOneTurn(), longer).empty());
}

// An estimate that tilts by 0.5 degrees about the world's x axis in the middle of the turn, and one that
// is off only in heading there: the first leaves 0.5 degrees, the second none.
TEST(TurnTilt, MeasuresTheTiltATurnLeavesAndNotTheHeading) {
  const std::vector<Pose3> gt = routeWithOneTurn();
  std::vector<Pose3> tilted = gt, turned = gt;
  for (size_t i = 55; i < gt.size(); ++i) {
    tilted[i].linear() = about(Eigen::Vector3d::UnitX(), 0.5) * gt[i].linear();
    turned[i].linear() = about(Eigen::Vector3d::UnitY(), 0.7) * gt[i].linear();
  }
  const auto turns = sharpTurns(gt);
  const auto t = tiltLeftByTurns(matched(gt, tilted), turns);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_NEAR(t[0].tilt_deg, 0.5, 1e-6);
  const auto h = tiltLeftByTurns(matched(gt, turned), turns);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_NEAR(h[0].tilt_deg, 0, 1e-6);
}

// The same tilted estimate, expressed in the world of its frame 30's camera (as `run --start 30` writes it)
// and turned half round: the same 0.5 degrees. Comparing world-frame errors instead read 13 degrees
// from such a run on rendered 06.
TEST(TurnTilt, TheEstimatesOwnWorldDoesNotMatter) {
  const std::vector<Pose3> gt = routeWithOneTurn();
  std::vector<Pose3> tilted = gt;
  for (size_t i = 55; i < gt.size(); ++i)
    tilted[i].linear() = about(Eigen::Vector3d::UnitX(), 0.5) * gt[i].linear();
  Pose3 elsewhere = Pose3::Identity();
  elsewhere.linear() = about(Eigen::Vector3d(0.1, 1, 0), 175);
  elsewhere.translation() = Eigen::Vector3d(40, -2, 7);
  const Pose3 to_frame30 = elsewhere * tilted[30].inverse();
  std::vector<Pose3> moved;
  for (const Pose3& T : tilted) moved.push_back(to_frame30 * T);
  const auto t = tiltLeftByTurns(matched(gt, moved), sharpTurns(gt));
  ASSERT_EQ(t.size(), 1u);
  EXPECT_NEAR(t[0].tilt_deg, 0.5, 1e-6);
}

TEST(TurnTilt, ATurnWhoseEndHasNoEstimateIsLeftOut) {
  const std::vector<Pose3> gt = routeWithOneTurn();
  MatchedPoses m = matched(gt, gt);
  m.frames.resize(60);  // the estimate stops in the middle of the turn
  m.gt.resize(60);
  m.est.resize(60);
  EXPECT_TRUE(tiltLeftByTurns(m, sharpTurns(gt)).empty());
}
