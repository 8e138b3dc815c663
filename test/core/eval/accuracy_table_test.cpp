// The accuracy benchmark's sums over runs, and a peer's run folders scored by the same rules.
#include "binloop/eval/accuracy_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "binloop/io/data_error.h"
#include "binloop/io/trajectory_io.h"
#include "support/test_support.h"

using namespace binloop;

namespace {

RunScore run(double ate, double t_rel, int accepted, int correct, std::vector<bool> closed, int lost) {
  RunScore s;
  s.metrics.ate_rmse_m = ate;
  s.metrics.relative.valid = true;
  s.metrics.relative.t_rel_pct = t_rel;
  s.metrics.relative.r_rel_deg_per_100m = t_rel / 2;
  s.loops.accepted = accepted;
  s.loops.correct = correct;
  s.loops.closed = std::move(closed);
  s.lost_frames = lost;
  return s;
}

// 1 m a frame along z for 0..200, then back along z: frame f and 400 - f are the same place.
std::vector<Pose3> outAndBack() {
  std::vector<Pose3> p;
  for (int i = 0; i <= 400; ++i) {
    Pose3 T = Pose3::Identity();
    T.translation().z() = i <= 200 ? i : 400 - i;
    p.push_back(T);
  }
  return p;
}

}  // namespace

TEST(AccuracyTable, MedianRangeWrongLoopsAndSegmentsClosedInEveryRun) {
  const AccuracyRow r =
      summarizeRuns("hbow",
                    {run(0.30, 0.20, 2, 2, {true, false}, 0), run(0.10, 0.10, 3, 2, {true, true}, 4),
                     run(0.20, NAN, 1, 1, {true, false}, 1)},
                    2);
  EXPECT_EQ(r.runs, 3);
  EXPECT_DOUBLE_EQ(r.ate_median, 0.20);
  EXPECT_DOUBLE_EQ(r.ate_min, 0.10);
  EXPECT_DOUBLE_EQ(r.ate_max, 0.30);
  EXPECT_NEAR(r.spread(), 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.t_rel_median, 0.15);  // the run without segments left out
  EXPECT_DOUBLE_EQ(r.loops_median, 2);
  EXPECT_EQ(r.loops_wrong, 1);
  EXPECT_EQ(r.segments_every_run, 1);  // the second segment was missed in two runs
  EXPECT_EQ(r.lost_max, 4);
  EXPECT_THROW_WITH(summarizeRuns("none", {}, 0), DataError, "no run");
}

TEST(AccuracyTable, APeersRunsAreGroupedByFolderAndScoredAlike) {
  test::TempDir tmp;
  const std::vector<Pose3> gt = outAndBack();
  namespace fs = std::filesystem;
  for (const char* d : {"loops-1", "loops-2", "no-loops"}) fs::create_directories(tmp / d);
  std::vector<Pose3> est = gt, drifted = gt;
  for (size_t i = 0; i < drifted.size(); ++i) drifted[i].translation().x() += 0.002 * static_cast<double>(i);
  writeKittiPoses(tmp / "loops-1/CameraTrajectory.txt", est);
  writeKittiPoses(tmp / "loops-2/CameraTrajectory.txt", est);
  writeKittiPoses(tmp / "no-loops/CameraTrajectory.txt", drifted);
  test::writeText(tmp / "loops-1/loops.txt", "350 50\n");   // the same place: closes the revisit
  test::writeText(tmp / "loops-2/loops.txt", "350 150\n");  // 100 m apart: wrong
  test::writeText(tmp / "loops-2/TrackingTimes.txt", "0 0.0 0.03 2\n1 0.1 0.03 3\n2 0.2 0.03 3\n");
  const std::vector<RevisitSegment> segments{{300, 399, 100}};
  const std::vector<AccuracyRow> rows = scorePeerRuns(tmp.path(), "peer:", gt, segments);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].name, "peer:loops");
  EXPECT_EQ(rows[0].runs, 2);
  EXPECT_NEAR(rows[0].ate_median, 0, 1e-6);
  EXPECT_EQ(rows[0].loops_wrong, 1);
  EXPECT_EQ(rows[0].segments_every_run, 0);  // closed in one run of two
  EXPECT_EQ(rows[0].lost_max, 2);
  EXPECT_EQ(rows[1].name, "peer:no-loops");
  EXPECT_GT(rows[1].ate_median, 0.05);
  const std::string table = formatAccuracyTable(rows, true);
  EXPECT_EQ(table.rfind("system,runs,ate_m_median,", 0), 0u) << table;
  EXPECT_NE(table.find("\npeer:loops,2,"), std::string::npos) << table;
  EXPECT_THROW_WITH(scorePeerRuns(tmp / "none", "peer:", gt, segments), DataError, "no such folder");
  test::writeText(tmp / "loops-1/TrackingTimes.txt", "0 0.0 tracked\n");
  EXPECT_THROW_WITH(scorePeerRuns(tmp.path(), "peer:", gt, segments), DataError,
                    "expected 'frame stamp seconds state'");
}
