#include "binloop/eval/loop_ground_truth.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "binloop/io/trajectory_io.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

TEST(LoopGroundTruth, PairsWithinTheRadiusAndOutsideTheGap) {
  // A 1 m-per-frame straight line out and back: frame 10 is at x=10, frame 20 back at x=0.
  std::vector<Pose3> p;
  for (int i = 0; i <= 20; ++i) {
    Pose3 T = Pose3::Identity();
    T.translation().x() = i <= 10 ? i : 20 - i;
    p.push_back(T);
  }
  const auto pairs = loopPairsFromPoses(p, 1.5, 5);
  const std::set<std::pair<int, int>> got(pairs.begin(), pairs.end());
  EXPECT_TRUE(got.count({20, 0}));
  EXPECT_TRUE(got.count({19, 1}));
  EXPECT_TRUE(got.count({19, 2}));   // 1 m apart
  EXPECT_FALSE(got.count({19, 3}));  // 2 m apart
  EXPECT_TRUE(got.count({13, 7}));   // the same place 6 frames apart: more than the gap of 5
  EXPECT_FALSE(got.count({12, 8}));  // the same place 4 frames apart: temporal neighbours
}

// The shipped KITTI 06 list was made with 6 m; poses give the same pairs for the revisit.
TEST(LoopGroundTruth, AgreesWithTheKitti06List) {
  const std::string poses = sharedData("kitti/poses/06.txt"), gt = sharedData("kitti/loop_gt/06.txt");
  BINLOOP_REQUIRE_DATA(poses);
  BINLOOP_REQUIRE_DATA(gt);
  const auto mine = loopPairsFromPoses(readKittiPoses(poses), 6.0, 300);
  std::set<std::pair<int, int>> list;
  for (const auto& pr : readIndexPairs(gt))
    if (pr.first - pr.second > 300) list.insert(pr);
  ASSERT_FALSE(list.empty());
  size_t shared = 0;
  for (const auto& pr : mine) shared += list.count(pr);
  EXPECT_GT(shared, 0.95 * list.size());
  EXPECT_GT(shared, 0.95 * mine.size());
}
