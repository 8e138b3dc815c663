#include "binloop/sim/level_revisits.h"

#include <stdexcept>

#include "support/pose_at.h"
#include "support/test_support.h"

using binloop::Pose3;
using namespace binloop::sim;
using binloop::test::poseAt;

// A street driven twice, the second time 4 m higher in the ground truth (y is down), with a detour between
// the passes that climbs the same 4 m: the second pass must come down onto the first, and the detour must
// fade into it without a step.
TEST(LevelRevisits, ARevisitTakesTheEarlierPassHeightAndTheChangeFadesAlongThePath) {
  std::vector<Pose3> route;
  for (int i = 0; i < 400; ++i) route.push_back(poseAt(0, 0, i));  // first pass, 1 m steps
  for (int i = 0; i < 400; ++i)
    route.push_back(poseAt(100, -4, 399 - i));                      // detour, 100 m away, back down the z
  for (int i = 0; i < 400; ++i) route.push_back(poseAt(1, -4, i));  // second pass, 1 m beside the first
  const LevelResult r = levelRevisits(route);
  ASSERT_EQ(r.route.size(), route.size());
  EXPECT_EQ(r.revisit_frames, 400u);
  EXPECT_NEAR(r.max_shift_m, 4.0, 1e-9);
  for (size_t i = 0; i < 400; ++i) EXPECT_EQ(r.route[i].translation(), route[i].translation()) << i;
  for (size_t i = 800; i < 1200; ++i) EXPECT_NEAR(r.route[i].translation().y(), 0.0, 1e-9) << i;
  // x and z never change.
  for (size_t i = 0; i < route.size(); ++i) {
    EXPECT_EQ(r.route[i].translation().x(), route[i].translation().x());
    EXPECT_EQ(r.route[i].translation().z(), route[i].translation().z());
  }
  // The detour: untouched more than 150 m of path before the revisit, then a ramp of 4 m per 150 m at most.
  // The jump from frame 399 to 400 (100 m) and from 799 to 800 (99 m) count as path.
  EXPECT_EQ(r.route[400].translation().y(), -4.0);
  EXPECT_EQ(r.route[740].translation().y(), -4.0);  // 59 + 99 = 158 m before frame 800
  for (size_t i = 401; i < 800; ++i) {
    const double step = (route[i].translation() - route[i - 1].translation()).norm();
    const double change = std::abs((r.route[i].translation().y() - route[i].translation().y()) -
                                   (r.route[i - 1].translation().y() - route[i - 1].translation().y()));
    EXPECT_LE(change, 4.0 / 150 * step + 1e-9) << i;
  }
  EXPECT_GT(r.route[799].translation().y(), -4.0 + 1.0);  // 99 m before: two thirds of the way down already
}

TEST(LevelRevisits, ARouteThatNeverComesBackIsUnchanged) {
  std::vector<Pose3> route;
  for (int i = 0; i < 1000; ++i) route.push_back(poseAt(0, -0.01 * i, i));  // a steady climb
  const LevelResult r = levelRevisits(route);
  EXPECT_EQ(r.revisit_frames, 0u);
  EXPECT_EQ(r.max_shift_m, 0.0);
  for (size_t i = 0; i < route.size(); ++i) EXPECT_EQ(r.route[i].translation(), route[i].translation());
  LevelParams bad;
  bad.radius_m = 0;
  EXPECT_THROW(levelRevisits(route, bad), std::invalid_argument);
  EXPECT_TRUE(levelRevisits({}).route.empty());
}
