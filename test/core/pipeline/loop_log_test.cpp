// loops.csv: what run writes is what eval-slam reads back, and a broken file is an error naming the line.
#include "binloop/pipeline/loop_log.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include "binloop/eval/slam_evaluation.h"
#include "binloop/io/data_error.h"

#include "support/test_support.h"

using namespace binloop;

namespace {

SlamPipeline::LoopLogEntry entry(uint64_t query, uint64_t frame, msg::LoopStatus status,
                                 uint64_t match_frame) {
  SlamPipeline::LoopLogEntry e;
  auto c = std::make_shared<msg::LoopCandidates>();
  c->query = query;
  c->query_frame = frame;
  c->model = "hbow";
  c->status = "found";
  c->detail = "a \"quoted\", detail";
  c->candidates.push_back({7, 0.25, 2.0});
  c->accepted = 7;
  e.active = c;
  auto l = std::make_shared<msg::LoopClosure>();
  l->query = query;
  l->query_frame = frame;
  l->match_frame = match_frame;
  l->model = "hbow";
  l->status = status;
  l->inliers = 120;
  l->correction_m = 1.5;
  l->detail = "numbers, with a comma";
  e.closures.push_back(l);
  auto s = std::make_shared<msg::LoopCandidates>(*c);
  s->model = "vlad";
  s->shadow = true;
  s->accepted = kNoId;
  e.shadow.push_back(s);
  return e;
}

}  // namespace

TEST(LoopLog, WhatIsWrittenIsReadBack) {
  test::TempDir tmp;
  writeLoopLog(tmp / "loops.csv", {entry(1, 30, msg::LoopStatus::kTooFewMatches, 2),
                                   entry(2, 40, msg::LoopStatus::kAccepted, 3)});
  const std::vector<LoggedLoop> loops = readLoopLog(tmp / "loops.csv");
  ASSERT_EQ(loops.size(), 2u);  // shadow rows carry no closure
  EXPECT_EQ(loops[0].status, msg::LoopStatus::kTooFewMatches);
  EXPECT_EQ(loops[1].status, msg::LoopStatus::kAccepted);
  EXPECT_EQ(loops[1].query_frame, 40u);
  EXPECT_EQ(loops[1].match_frame, 3u);
  EXPECT_EQ(loops[1].inliers, 120);
  EXPECT_DOUBLE_EQ(loops[1].correction_m, 1.5);
}

TEST(LoopLog, ABrokenFileNamesTheLine) {
  test::TempDir tmp;
  writeLoopLog(tmp / "loops.csv", {entry(1, 30, msg::LoopStatus::kAccepted, 2)});
  std::ifstream in(tmp / "loops.csv");
  std::stringstream text;
  text << in.rdbuf();
  test::writeText(tmp / "short.csv", text.str() + "1,2,3\n");
  EXPECT_THROW_WITH(readLoopLog(tmp / "short.csv"), DataError, "short.csv:4: 3 fields, expected 24");
  test::writeText(tmp / "header.csv", "frame,model\n");
  EXPECT_THROW_WITH(readLoopLog(tmp / "header.csv"), DataError, "not a loops.csv");
  EXPECT_THROW_WITH(readLoopLog(tmp / "missing.csv"), DataError, "cannot open");
  std::string renamed = text.str();
  renamed.replace(renamed.find(",accepted,"), 10, ",approved,");
  test::writeText(tmp / "status.csv", renamed);
  EXPECT_THROW_WITH(readLoopLog(tmp / "status.csv"), DataError, "unknown loop status 'approved'");
}

// Each verified loop's relative pose is logged and read back; with ground truth its error is logged too.
TEST(LoopLog, ARelativePoseAndItsErrorAgainstTheGroundTruth) {
  test::TempDir tmp;
  SlamPipeline::LoopLogEntry e = entry(2, 4, msg::LoopStatus::kAccepted, 1);
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(0.2, 0, -3.0);  // the match 3 m behind, 0.2 m off sideways
  T.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  auto c = std::make_shared<msg::LoopClosure>(*e.closures[0]);
  c->T_query_match = T;
  e.closures[0] = c;
  // Ground truth: frame k at z = k metres, no rotation; so the truth is (0, 0, -3), no turn.
  std::vector<Pose3> gt(5, Pose3::Identity());
  for (int k = 0; k < 5; ++k) gt[k].translation().z() = k;
  writeLoopLog(tmp / "loops.csv", {e}, &gt);
  const std::vector<LoggedLoop> loops = readLoopLog(tmp / "loops.csv");
  ASSERT_EQ(loops.size(), 1u);
  ASSERT_TRUE(loops[0].has_pose);
  EXPECT_TRUE(loops[0].T_query_match.isApprox(T, 1e-6));
  const std::string text = [&] {
    std::ifstream in(tmp / "loops.csv");
    std::stringstream t;
    t << in.rdbuf();
    return t.str();
  }();
  const LoopPoseError err = loopPoseError(4, 1, T, gt);
  EXPECT_NEAR(err.rotation_deg, 0.05 * 180 / M_PI, 1e-6);
  EXPECT_NEAR(err.translation_m, 0.2, 1e-9);  // the truth is (0, 0, -3): 0.2 m sideways off
  std::ostringstream expected;
  expected << "," << err.translation_m << "," << err.rotation_deg << "\n";
  EXPECT_NE(text.find(expected.str()), std::string::npos) << text;
}

// A loops.csv written before the relative pose was logged still reads, without poses.
TEST(LoopLog, AnOlderLogWithoutPosesStillReads) {
  test::TempDir tmp;
  writeLoopLog(tmp / "loops.csv", {entry(2, 40, msg::LoopStatus::kAccepted, 3)});
  std::ifstream in(tmp / "loops.csv");
  std::string line, old;
  while (std::getline(in, line)) {
    // Drop the three last fields (query_to_match, gt_error_m, gt_error_deg).
    for (int i = 0; i < 3; ++i) line = line.substr(0, line.rfind(','));
    old += line + "\n";
  }
  test::writeText(tmp / "old.csv", old);
  const std::vector<LoggedLoop> loops = readLoopLog(tmp / "old.csv");
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_FALSE(loops[0].has_pose);
  EXPECT_EQ(loops[0].match_frame, 3u);
}
