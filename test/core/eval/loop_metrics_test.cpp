#include "binloop/eval/loop_metrics.h"

#include <gtest/gtest.h>

using namespace binloop;

TEST(LoopMetrics, PrecisionRecallByHand) {
  // Four queries with a loop (10..13, true refs 0..3); predictions ranked 0.9 ✓, 0.8 ✓, 0.7 ✗, 0.6 ✓;
  // query 13 predicts nothing and 14 (no loop) predicts a false loop at 0.7.
  const std::set<std::pair<int, int>> truth{{10, 0}, {11, 1}, {12, 2}, {13, 3}};
  const std::set<int> positives{10, 11, 12, 13};
  const std::vector<LoopPrediction> p{{10, 0, 0.9}, {11, 1, 0.8}, {14, 5, 0.7}, {12, 2, 0.6}, {13, -1, 0}};
  const LoopMetrics m = evaluateLoops(p, truth, positives);
  EXPECT_DOUBLE_EQ(m.r_at_100p, 0.5);
  EXPECT_DOUBLE_EQ(m.threshold_100p, 0.8);
  ASSERT_EQ(m.curve.size(), 4u);
  EXPECT_DOUBLE_EQ(m.curve[3].precision, 0.75);
  EXPECT_DOUBLE_EQ(m.curve[3].recall, 0.75);
  EXPECT_DOUBLE_EQ(m.auc, 1.0 * 0.25 + 1.0 * 0.25 + 0.75 * 0.25);
  EXPECT_EQ(foundAt(p, truth, {12, 13}, 0.5), 1);
}

TEST(LoopMetrics, TiesEnterTogether) {
  // A true and a false prediction with the same confidence: no threshold keeps only the true one.
  const std::vector<LoopPrediction> p{{10, 0, 0.5}, {11, 7, 0.5}};
  const LoopMetrics m = evaluateLoops(p, {{10, 0}, {11, 1}}, {10, 11});
  EXPECT_DOUBLE_EQ(m.r_at_100p, 0.0);
}

TEST(LoopMetrics, HigherTierRanksFirst) {
  // A false prediction of tier 0 with a high confidence ranks below a true one of tier 1.
  std::vector<LoopPrediction> p{{10, 0, 0.2}, {11, 7, 5.0}};
  p[0].tier = 1;
  const LoopMetrics m = evaluateLoops(p, {{10, 0}, {11, 1}}, {10, 11});
  EXPECT_DOUBLE_EQ(m.r_at_100p, 0.5);
  EXPECT_EQ(m.tier_100p, 1);
  EXPECT_EQ(foundAt(p, {{10, 0}, {11, 1}}, {10}, m.threshold_100p, m.tier_100p), 1);
}

TEST(LoopMetrics, IgnoredPairsCountNeitherRightNorWrong) {
  // Query 14's false loop at 0.7 is a near miss: ignored, it no longer stops the recall at 100 % precision.
  // An ignored pair that the truth lists still counts as right.
  const std::set<std::pair<int, int>> truth{{10, 0}, {11, 1}, {12, 2}};
  const std::vector<LoopPrediction> p{{10, 0, 0.9}, {14, 5, 0.7}, {11, 1, 0.6}, {12, 8, 0.5}};
  EXPECT_DOUBLE_EQ(evaluateLoops(p, truth, {10, 11, 12}).r_at_100p, 1.0 / 3);
  const LoopMetrics m = evaluateLoops(p, truth, {10, 11, 12}, {{14, 5}, {10, 0}});
  EXPECT_DOUBLE_EQ(m.r_at_100p, 2.0 / 3);
  ASSERT_EQ(m.curve.size(), 3u);
  EXPECT_DOUBLE_EQ(m.curve.back().precision, 2.0 / 3);
}
