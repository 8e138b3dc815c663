#include "binloop/io/trajectory_io.h"

#include "binloop/io/data_error.h"
#include "binloop/io/kitti_calib.h"
#include "support/test_support.h"

using binloop::DataError;
using binloop::Pose3;
using binloop::test::TempDir;
using binloop::test::writeText;

namespace {
Pose3 somePose(double a) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(a, -2 * a, 10 + a);
  return T;
}
}  // namespace

TEST(TrajectoryIo, KittiRoundTrip) {
  TempDir tmp;
  std::vector<Pose3> poses{somePose(0.1), somePose(-1.2), somePose(2.5)};
  binloop::writeKittiPoses(tmp / "p.txt", poses);
  const auto back = binloop::readKittiPoses(tmp / "p.txt");
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) EXPECT_TRUE(back[i].isApprox(poses[i], 1e-8));
}

TEST(TrajectoryIo, TumRoundTrip) {
  TempDir tmp;
  binloop::Trajectory traj{{1.5, somePose(0.3)}, {1.6, somePose(0.4)}};
  binloop::writeTumTrajectory(tmp / "t.txt", traj);
  const auto back = binloop::readTumTrajectory(tmp / "t.txt");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_DOUBLE_EQ(back[1].stamp_s, 1.6);
  EXPECT_TRUE(back[1].T_w_c.isApprox(traj[1].T_w_c, 1e-8));
}

TEST(TrajectoryIo, ShortPoseLine) {
  TempDir tmp;
  writeText(tmp / "p.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_THROW_WITH(binloop::readKittiPoses(tmp / "p.txt"), DataError,
                    "p.txt:2: a KITTI pose (3x4 matrix, row-major) needs 12 numbers, found 11");
}

TEST(TrajectoryIo, NotARotation) {
  TempDir tmp;
  writeText(tmp / "p.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THROW_WITH(binloop::readKittiPoses(tmp / "p.txt"), DataError,
                    "p.txt:1: the 3x3 part is not a rotation");
}

TEST(TrajectoryIo, TimesGoingBackwards) {
  TempDir tmp;
  writeText(tmp / "times.txt", "0.0\n0.1\n0.05\n");
  EXPECT_THROW_WITH(binloop::readTimes(tmp / "times.txt"), DataError, "times.txt:3: time goes backwards");
}

TEST(TrajectoryIo, IndexPairsWithComments) {
  TempDir tmp;
  writeText(tmp / "gt.txt", "# query ref\n830 0\n\n831 2\n");
  const auto pairs = binloop::readIndexPairs(tmp / "gt.txt");
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[1], std::make_pair(831, 2));
  writeText(tmp / "bad.txt", "830 0.5\n");
  EXPECT_THROW_WITH(binloop::readIndexPairs(tmp / "bad.txt"), DataError, "bad.txt:1: indices must be whole");
}

TEST(KittiCalib, RoundTripAndBaseline) {
  TempDir tmp;
  const auto cam = binloop::kitti00Camera();
  binloop::writeKittiCalib(tmp / "calib.txt", cam);
  auto back = binloop::readKittiCalib(tmp / "calib.txt");
  back.width = cam.width;
  back.height = cam.height;
  EXPECT_NEAR(back.baseline_m, cam.baseline_m, 1e-12);
  EXPECT_DOUBLE_EQ(back.fx, 718.856);
}

TEST(KittiCalib, PositiveP1TranslationIsRefused) {
  TempDir tmp;
  writeText(tmp / "calib.txt",
            "P0: 700 0 600 0 0 700 180 0 0 0 1 0\nP1: 700 0 600 386 0 700 180 0 0 0 1 0\n");
  EXPECT_THROW_WITH(binloop::readKittiCalib(tmp / "calib.txt"), DataError,
                    "calib.txt:2: P1[0][3] must be -fx*baseline");
}
