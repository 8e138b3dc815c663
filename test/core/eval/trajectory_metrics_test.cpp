#include "binloop/eval/trajectory_metrics.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "binloop/eval/trajectory_plot.h"
#include "binloop/io/data_error.h"
#include "binloop/io/trajectory_io.h"
#include "support/test_support.h"

using namespace binloop;
using binloop::test::TempDir;
using binloop::test::writeText;

namespace {

const double kDeg = M_PI / 180.0;

Pose3 pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Matrix3d yaw(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

// n poses 1 m apart straight along z (KITTI: forward), no rotation.
std::vector<Pose3> straightLine(int n) {
  std::vector<Pose3> p;
  for (int i = 0; i < n; ++i) p.push_back(pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, i)));
  return p;
}

// A winding, slightly hilly drive of n frames ~1 m apart, heading along the path.
std::vector<Pose3> windingDrive(int n) {
  std::vector<Pose3> p;
  Eigen::Vector3d t(0, 0, 0);
  double heading = 0;
  for (int i = 0; i < n; ++i) {
    heading += 0.02 * std::sin(i / 40.0);
    const Eigen::Matrix3d R =
        yaw(heading) * Eigen::AngleAxisd(0.03 * std::cos(i / 25.0), Eigen::Vector3d::UnitX());
    p.push_back(pose(R, t));
    t += R * Eigen::Vector3d(0, 0, 1.0);
  }
  return p;
}

EstimateFile kittiEstimate(const std::vector<Pose3>& poses) {
  EstimateFile f;
  f.format = TrajectoryFormat::kitti;
  for (size_t i = 0; i < poses.size(); ++i) f.poses.push_back({static_cast<double>(i), poses[i]});
  return f;
}

// The estimate of every `stride`-th frame, as a TUM file whose stamps are `stamp(frame)`.
template <class Stamp>
EstimateFile tumEstimate(const std::vector<Pose3>& poses, int stride, Stamp stamp) {
  EstimateFile f;
  f.format = TrajectoryFormat::tum;
  for (size_t i = 0; i < poses.size(); i += stride) f.poses.push_back({stamp(static_cast<int>(i)), poses[i]});
  return f;
}

TrajectoryMetrics evalAll(const std::vector<Pose3>& gt, const std::vector<Pose3>& est) {
  return evaluateTrajectory(matchByFrameIndex(gt, kittiEstimate(est)));
}

// Segments of a straight 1 m-per-frame line of `metres`, starts every 10 frames, lengths 100..800.
int segmentCount(int metres) {
  int n = 0;
  for (int len = 100; len <= 800; len += 100)
    if (len <= metres) n += (metres - len) / 10 + 1;
  return n;
}

}  // namespace

TEST(TrajectoryMetrics, IdenticalTrajectoriesHaveNoError) {
  const auto gt = windingDrive(1200);
  const TrajectoryMetrics m = evalAll(gt, gt);
  EXPECT_NEAR(m.ate_rmse_m, 0, 1e-9);
  ASSERT_TRUE(m.relative.valid);
  EXPECT_GT(m.relative.segments, 0);
  EXPECT_NEAR(m.relative.t_rel_pct, 0, 1e-9);
  EXPECT_NEAR(m.relative.r_rel_deg_per_100m, 0, 1e-5);  // acos near 1 resolves ~1e-8 rad
  EXPECT_TRUE(m.T_gt_est.isApprox(Pose3::Identity(), 1e-9));
}

TEST(TrajectoryMetrics, RigidlyMovedEstimateHasNoErrorAfterAlignment) {
  const auto gt = windingDrive(1200);
  const Pose3 T_est_gt =
      pose(Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.2, -1, 0.5).normalized()).toRotationMatrix(),
           Eigen::Vector3d(30, -4, 120));
  std::vector<Pose3> est;
  for (const auto& T : gt) est.push_back(T_est_gt * T);
  const TrajectoryMetrics m = evalAll(gt, est);
  EXPECT_NEAR(m.ate_rmse_m, 0, 1e-6);
  EXPECT_TRUE(m.T_gt_est.isApprox(T_est_gt.inverse(), 1e-9));
  EXPECT_NEAR(m.relative.t_rel_pct, 0, 1e-9);
  EXPECT_NEAR(m.relative.r_rel_deg_per_100m, 0, 1e-5);
}

TEST(TrajectoryMetrics, ConstantTranslationIsAlignedAway) {
  const auto gt = windingDrive(300);
  const Eigen::Vector3d d(1.5, -0.5, 3);
  std::vector<Pose3> est = gt;
  for (auto& T : est) T.translation() += d;
  const TrajectoryMetrics m = evalAll(gt, est);
  EXPECT_NEAR(m.ate_rmse_m, 0, 1e-9);
  EXPECT_TRUE(m.T_gt_est.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-9));
  EXPECT_TRUE(m.T_gt_est.translation().isApprox(-d, 1e-9));
}

TEST(TrajectoryMetrics, OneDisplacedFrame) {
  // On a line, a frame moved by d along it: the alignment shifts everything by d/N, leaving N-1 errors of
  // d/N and one of d (N-1)/N, so the RMSE is d sqrt(N-1) / N.
  const int n = 50;
  const double d = 2.0;
  const auto gt = straightLine(n);
  auto est = gt;
  est[17].translation().z() += d;
  EXPECT_NEAR(evalAll(gt, est).ate_rmse_m, d * std::sqrt(n - 1.0) / n, 1e-9);
}

TEST(TrajectoryMetrics, ScaleDriftOfOnePercentIsOnePercent) {
  const auto gt = straightLine(1001);  // 1000 m
  std::vector<Pose3> est = gt;
  for (auto& T : est) T.translation() *= 1.01;
  const TrajectoryMetrics m = evalAll(gt, est);
  ASSERT_TRUE(m.relative.valid);
  EXPECT_EQ(m.relative.segments, segmentCount(1000));  // 448
  EXPECT_DOUBLE_EQ(m.relative.path_length_m, 1000);
  EXPECT_NEAR(m.relative.t_rel_pct, 1.0, 1e-9);
  EXPECT_NEAR(m.relative.r_rel_deg_per_100m, 0, 1e-5);
}

TEST(TrajectoryMetrics, YawDriftPerMetreIsTheRotationError) {
  // The estimate turns 0.01 deg about the camera's y axis per metre driven while the truth goes straight:
  // every segment of L metres ends 0.01 L deg off, i.e. 1 deg per 100 m.
  const auto gt = straightLine(1001);
  const double w = 0.01 * kDeg;
  std::vector<Pose3> est;
  Eigen::Vector3d t(0, 0, 0);
  for (int i = 0; i < 1001; ++i) {
    est.push_back(pose(yaw(w * i), t));
    t += yaw(w * i) * Eigen::Vector3d(0, 0, 1);
  }
  const TrajectoryMetrics m = evalAll(gt, est);
  ASSERT_TRUE(m.relative.valid);
  EXPECT_NEAR(m.relative.r_rel_deg_per_100m, 1.0, 1e-6);
  EXPECT_GT(m.relative.t_rel_pct, 0.1);  // the turned heading also displaces the end of each segment
}

TEST(TrajectoryMetrics, KeyframesByIndexUseOnlyMatchedFrames) {
  const auto gt = straightLine(1001);
  std::vector<Pose3> est = gt;
  for (auto& T : est) T.translation() *= 1.01;
  // Every 5th frame: segments still start at frames 0, 10, 20, ... and end exactly L metres on.
  const MatchedPoses m = matchByFrameIndex(gt, tumEstimate(est, 5, [](int f) { return double(f); }));
  ASSERT_EQ(m.frames.size(), 201u);
  EXPECT_EQ(m.frames[3], 15);
  EXPECT_EQ(m.rule, "by frame index (TUM stamp = frame)");
  const TrajectoryMetrics tm = evaluateTrajectory(m);
  EXPECT_EQ(tm.relative.segments, segmentCount(1000));
  EXPECT_NEAR(tm.relative.t_rel_pct, 1.0, 1e-9);
}

TEST(TrajectoryMetrics, SegmentsStartAtTheFirstKeyframeOfEachTenFrames) {
  // Keyframes every 7 frames of a 1 m-per-frame line, 140 m: the ones at or after frames 0, 10, 20, ...
  // are 0, 14, 21, 35, 42, 56, ...; segments of 100 m end 105 m on (the next keyframe) from 0, 14, 21,
  // 35 only (from 42, 147 m is past the end).
  const auto gt = straightLine(141);
  std::vector<Pose3> est = gt;
  for (auto& T : est) T.translation() *= 1.01;
  const MatchedPoses m = matchByFrameIndex(gt, tumEstimate(est, 7, [](int f) { return double(f); }));
  const RelativeErrors r = kittiRelativeErrors(m);
  EXPECT_EQ(r.segments, 4);
  EXPECT_NEAR(r.t_rel_pct, 1.0 * 105 / 100, 1e-9);  // 1 % of the 105 m actually driven, over 100 m
}

TEST(TrajectoryMetrics, KeyframesByTime) {
  const auto gt = windingDrive(400);
  std::vector<double> times;
  for (int i = 0; i < 400; ++i) times.push_back(0.1036 * i + 0.0003 * std::sin(i));
  // Stamps 0.4 ms off their frames' times, and 1 s later as in kitti2bag's bags.
  const auto est = tumEstimate(gt, 3, [&](int f) { return times[f] + 1.0004; });
  TimeMatchOptions o;
  o.stamp_offset_s = 1.0;
  const MatchedPoses m = matchByTime(gt, times, est, o);
  ASSERT_EQ(m.frames.size(), 134u);
  for (size_t k = 0; k < m.frames.size(); ++k) ASSERT_EQ(m.frames[k], static_cast<int>(3 * k));
  EXPECT_NE(m.rule.find("by time stamp"), std::string::npos);
  EXPECT_NEAR(evaluateTrajectory(m).ate_rmse_m, 0, 1e-9);
  // Without the offset no stamp is within 1 ms of a frame.
  EXPECT_THROW_WITH(matchByTime(gt, times, est), DataError, "from the nearest ground-truth time");
}

TEST(TrajectoryMetrics, ShortTrajectoryHasNoRelativeErrors) {
  const auto gt = straightLine(60);  // 59 m
  const TrajectoryMetrics m = evalAll(gt, gt);
  EXPECT_FALSE(m.relative.valid);
  EXPECT_TRUE(std::isnan(m.relative.t_rel_pct));
  EXPECT_TRUE(std::isnan(m.relative.r_rel_deg_per_100m));
  EXPECT_NE(m.relative.reason.find("59.0 m, less than the shortest segment (100 m)"), std::string::npos)
      << m.relative.reason;
  EXPECT_NEAR(m.ate_rmse_m, 0, 1e-9);
}

TEST(TrajectoryMetrics, ReadsBothFormats) {
  TempDir tmp;
  const auto gt = windingDrive(20);
  writeKittiPoses(tmp / "k.txt", gt);
  Trajectory traj;
  for (int i = 0; i < 20; i += 4) traj.push_back({0.1 * i, gt[i]});
  writeTumTrajectory(tmp / "t.txt", traj);
  const EstimateFile k = readEstimateFile(tmp / "k.txt"), t = readEstimateFile(tmp / "t.txt");
  EXPECT_EQ(k.format, TrajectoryFormat::kitti);
  ASSERT_EQ(k.poses.size(), 20u);
  EXPECT_EQ(k.poses[7].stamp_s, 7);
  EXPECT_EQ(t.format, TrajectoryFormat::tum);
  ASSERT_EQ(t.poses.size(), 5u);
  EXPECT_TRUE(t.poses[2].T_w_c.isApprox(gt[8], 1e-8));
}

TEST(TrajectoryMetrics, FileErrors) {
  TempDir tmp;
  const std::string I = "1 0 0 0 0 1 0 0 0 0 1 ";
  writeText(tmp / "empty.txt", "# nothing\n\n");
  EXPECT_THROW_WITH(readEstimateFile(tmp / "empty.txt"), DataError, "empty.txt: holds no poses");
  EXPECT_THROW_WITH(readGroundTruthPoses(tmp / "empty.txt"), DataError, "empty.txt: holds no poses");
  writeText(tmp / "nan.txt", I + "0\n" + I + "nan\n");
  EXPECT_THROW_WITH(readEstimateFile(tmp / "nan.txt"), DataError,
                    "nan.txt:2: holds a number that is not finite");
  EXPECT_THROW_WITH(readGroundTruthPoses(tmp / "nan.txt"), DataError,
                    "nan.txt:2: holds a number that is not finite");
  writeText(tmp / "mixed.txt", I + "0\n0 0 0 0 0 0 0 1\n");
  EXPECT_THROW_WITH(readEstimateFile(tmp / "mixed.txt"), DataError,
                    "mixed.txt:2: has 8 numbers, but the first pose line has 12 (KITTI)");
  writeText(tmp / "seven.txt", "0 0 0 0 0 0 1\n");
  EXPECT_THROW_WITH(readEstimateFile(tmp / "seven.txt"), DataError, "needs 12 numbers (KITTI) or 8 (TUM");
}

TEST(TrajectoryMetrics, MatchingErrors) {
  const auto gt = straightLine(10);
  // A KITTI estimate longer than the ground truth.
  EXPECT_THROW_WITH(matchByFrameIndex(gt, kittiEstimate(straightLine(11))), DataError,
                    "11 poses, but the ground truth has only 10");
  // TUM stamps as indices: beyond the ground truth, not whole, repeated.
  auto est = tumEstimate(gt, 1, [](int f) { return double(f) + 5; });
  EXPECT_THROW_WITH(matchByFrameIndex(gt, est), DataError,
                    "pose 6 is frame 10, but the ground truth has only 10");
  est = tumEstimate(gt, 1, [](int f) { return f * 0.1; });
  EXPECT_THROW_WITH(matchByFrameIndex(gt, est), DataError,
                    "pose 2 has stamp 0.1, which is not a frame index");
  est = tumEstimate(gt, 1, [](int f) { return double(f / 2); });
  EXPECT_THROW_WITH(matchByFrameIndex(gt, est), DataError, "poses 1 and 2 both match ground-truth frame 0");
  // By time: the times must match the ground truth, and KITTI files have no stamps.
  EXPECT_THROW_WITH(matchByTime(gt, {0, 0.1}, est), DataError, "the times file has 2 stamps for 10");
  EXPECT_THROW_WITH(matchByTime(gt, std::vector<double>(10, 0), kittiEstimate(gt)), DataError,
                    "no time stamps");
  // Too few poses, and poses that are not finite.
  const MatchedPoses two = matchByFrameIndex(gt, tumEstimate(gt, 5, [](int f) { return double(f); }));
  EXPECT_THROW_WITH(evaluateTrajectory(two), DataError,
                    "only 2 poses matched the ground truth; at least 3 are needed");
  MatchedPoses bad = matchByFrameIndex(gt, kittiEstimate(gt));
  bad.est[4].translation().x() = std::nan("");
  EXPECT_THROW_WITH(evaluateTrajectory(bad), DataError, "the estimated pose of frame 4 is not finite");
}

TEST(TrajectoryMetrics, UmeyamaNeedsThreeEqualPairs) {
  const std::vector<Eigen::Vector3d> a{{0, 0, 0}, {1, 0, 0}}, b{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW_WITH(alignUmeyama(a, a), DataError, "at least 3");
  EXPECT_THROW_WITH(alignUmeyama(a, b), DataError, "as many");
  // A mirrored point set still gets a proper rotation.
  const std::vector<Eigen::Vector3d> c{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
      mirrored{{0, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_NEAR(alignUmeyama(c, mirrored).linear().determinant(), 1.0, 1e-12);
}

TEST(TrajectoryPlot, WritesAReadablePng) {
  TempDir tmp;
  const auto gt = windingDrive(600);
  std::vector<Pose3> est = gt;
  for (auto& T : est) T.translation() *= 1.02;
  const MatchedPoses m = matchByFrameIndex(gt, kittiEstimate(est));
  const TrajectoryMetrics tm = evaluateTrajectory(m);
  std::vector<Pose3> aligned;
  for (const auto& T : est) aligned.push_back(tm.T_gt_est * T);
  writeTrajectoryPlot(tmp / "p.png", "test", gt, aligned, tm);
  const cv::Mat img = cv::imread(tmp / "p.png");
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 900);
  EXPECT_EQ(img.rows, 1000);
  EXPECT_THROW_WITH(writeTrajectoryPlot(tmp / "no/such/dir/p.png", "t", gt, aligned, tm), DataError,
                    "cannot write the plot");
}
