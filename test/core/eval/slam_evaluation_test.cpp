#include "binloop/eval/slam_evaluation.h"

#include <gtest/gtest.h>

#include "binloop/io/data_error.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

// 1 m per frame along x for frames 0..100, then back along x from 100 down to 0 (frames 100..200), so
// frame f and frame 200 - f lie at the same place.
std::vector<Pose3> outAndBack() {
  std::vector<Pose3> p;
  for (int i = 0; i <= 200; ++i) {
    Pose3 T = Pose3::Identity();
    T.translation().x() = i <= 100 ? i : 200 - i;
    p.push_back(T);
  }
  return p;
}

}  // namespace

TEST(RevisitSegments, SplitWhereQueryFramesJumpByMoreThanTheGap) {
  // Queries 50..60 with a hole of 20 frames (60 -> 80 stays together), then 101 after a jump of 21.
  const std::vector<std::pair<int, int>> pairs{{80, 3}, {50, 1},  {50, 2},  {55, 4},
                                               {60, 5}, {101, 7}, {103, 8}, {200, 0}};
  const auto s = revisitSegments(pairs);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].first, 50);
  EXPECT_EQ(s[0].last, 80);
  EXPECT_EQ(s[0].queries, 4);  // 50 counted once
  EXPECT_EQ(s[1].first, 101);
  EXPECT_EQ(s[1].last, 103);
  EXPECT_EQ(s[2].first, 200);
  EXPECT_EQ(s[2].last, 200);
  EXPECT_EQ(revisitSegments(pairs, 25).size(), 2u);  // 80 -> 101 now within the gap
  EXPECT_TRUE(revisitSegments({}).empty());
}

TEST(LoopScore, AWrongLoopIsCountedButClosesNothing) {
  const auto gt = outAndBack();
  EXPECT_TRUE(loopIsCorrect(150, 50, gt));   // the same place
  EXPECT_TRUE(loopIsCorrect(150, 41, gt));   // 9 m apart
  EXPECT_FALSE(loopIsCorrect(150, 39, gt));  // 11 m apart
  const std::vector<RevisitSegment> segments{{140, 160, 21}};
  const LoopScore s = scoreLoops({{150, 10}}, gt, segments);  // 40 m off, inside the segment
  EXPECT_EQ(s.accepted, 1);
  EXPECT_EQ(s.correct, 0);
  ASSERT_EQ(s.closed.size(), 1u);
  EXPECT_FALSE(s.closed[0]);
  EXPECT_EQ(s.segmentsClosed(), 0);
}

TEST(LoopScore, ACorrectLoopClosesOnlyTheSegmentHoldingItsQuery) {
  const auto gt = outAndBack();
  const std::vector<RevisitSegment> segments{{120, 140, 21}, {160, 180, 21}};
  // 170 -> 30 closes the second segment; 150 -> 50 is right but between the segments; 141 lies one frame
  // past the first one.
  const LoopScore s = scoreLoops({{170, 30}, {150, 50}, {141, 59}}, gt, segments);
  EXPECT_EQ(s.accepted, 3);
  EXPECT_EQ(s.correct, 3);
  EXPECT_EQ(s.closed, (std::vector<bool>{false, true}));
  EXPECT_EQ(s.segmentsClosed(), 1);
  // The segment's ends count as inside.
  EXPECT_EQ(scoreLoops({{120, 80}, {180, 20}}, gt, segments).closed, (std::vector<bool>{true, true}));
}

TEST(LoopScore, AFrameOutsideTheGroundTruthIsAnError) {
  const auto gt = outAndBack();
  EXPECT_THROW_WITH(scoreLoops({{250, 10}}, gt, {}), DataError,
                    "frame 250 is outside the 201 ground-truth poses");
}

// A loop between frames at the same place whose relative pose is 1.5 m or 3 degrees off is wrong: it would
// bend the map, so it neither counts as correct nor closes its segment.
TEST(LoopScore, ALoopWithAWrongRelativePoseClosesNothing) {
  const auto gt = outAndBack();
  const std::vector<RevisitSegment> segments{{140, 160, 21}};
  const Pose3 truth = gt[150].inverse() * gt[50];  // identity: the same place
  Pose3 off = truth;
  off.translation().x() += 1.5;
  Pose3 turned = truth;
  turned.linear() = Eigen::AngleAxisd(3.0 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Pose3 close = truth;
  close.translation().z() += 0.5;
  EXPECT_NEAR(loopPoseError(150, 50, off, gt).translation_m, 1.5, 1e-9);
  EXPECT_NEAR(loopPoseError(150, 50, turned, gt).rotation_deg, 3.0, 1e-9);
  EXPECT_FALSE(loopPoseIsWrong(loopPoseError(150, 50, close, gt)));

  const LoopScore wrong = scoreLoops({{150, 50}, {151, 49}}, {off, turned}, gt, segments);
  EXPECT_EQ(wrong.accepted, 2);
  EXPECT_EQ(wrong.correct, 0);
  EXPECT_EQ(wrong.wrong_pose, 2);
  EXPECT_EQ(wrong.segmentsClosed(), 0);
  const LoopScore right = scoreLoops({{150, 50}, {151, 49}}, {close, turned}, gt, segments);
  EXPECT_EQ(right.accepted, 2);
  EXPECT_EQ(right.correct, 1);
  EXPECT_EQ(right.wrong_pose, 1);
  EXPECT_EQ(right.segmentsClosed(), 1);
  EXPECT_THROW_WITH(scoreLoops({{150, 50}}, {}, gt, segments), DataError, "1 loops but 0 relative poses");
}
