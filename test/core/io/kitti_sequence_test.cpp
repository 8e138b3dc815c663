// The KITTI reader against the real sample of sequence 00, and every malformed-input case with the
// message the user sees.
#include "binloop/io/kitti_sequence.h"

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "binloop/io/data_error.h"
#include "binloop/io/trajectory_io.h"
#include "support/test_support.h"

namespace fs = std::filesystem;
using binloop::DataError;
using binloop::KittiSequence;
using binloop::test::sharedData;
using binloop::test::TempDir;
using binloop::test::writeText;

namespace {
std::string sample() { return sharedData("kitti/sample_00"); }

// A writable copy of the real sample, to break one thing at a time.
std::string copySample(const TempDir& tmp) {
  const std::string dst = tmp / "seq";
  binloop::test::copyTree(sample(), dst);
  return dst;
}
}  // namespace

TEST(KittiSequence, ReadsTheRealSample) {
  BINLOOP_REQUIRE_DATA(sample());
  const auto seq = KittiSequence::open(sample());
  ASSERT_EQ(seq.size(), 11u);
  EXPECT_EQ(seq.camera().width, 1241);
  EXPECT_EQ(seq.camera().height, 376);
  EXPECT_DOUBLE_EQ(seq.camera().fx, 718.856);
  EXPECT_NEAR(seq.camera().baseline_m, 0.537, 0.001);
  EXPECT_NEAR(seq.camera().bf(), 386.1448, 1e-9);
  ASSERT_TRUE(seq.hasPoses());
  ASSERT_EQ(seq.poses().size(), 11u);

  // Compare with the files themselves: the last line of times.txt and poses.txt.
  std::ifstream times(sample() + "/times.txt");
  double t = 0, last_t = 0;
  while (times >> t) last_t = t;
  EXPECT_DOUBLE_EQ(seq.times().back(), last_t);
  std::ifstream poses(sample() + "/poses.txt");
  std::string line, last_line;
  while (std::getline(poses, line))
    if (!line.empty()) last_line = line;
  std::istringstream ss(last_line);
  double m[12];
  for (double& v : m) ss >> v;
  const Eigen::Vector3d t_last = seq.poses().back().translation();
  EXPECT_NEAR(t_last.x(), m[3], 1e-9);
  EXPECT_NEAR(t_last.y(), m[7], 1e-9);
  EXPECT_NEAR(t_last.z(), m[11], 1e-9);
  EXPECT_NEAR(seq.poses().back().linear()(0, 1), m[1], 1e-6);

  for (size_t i = 0; i < seq.size(); ++i) {
    const auto f = seq.load(i);
    EXPECT_EQ(f.left.type(), CV_8UC1);
    EXPECT_EQ(f.left.cols, 1241);
    EXPECT_EQ(f.right.rows, 376);
    const cv::Mat raw = cv::imread(seq.leftPath(i), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(cv::norm(raw, f.left, cv::NORM_INF), 0.0);
  }
}

TEST(KittiSequence, MissingFolder) {
  EXPECT_THROW_WITH(KittiSequence::open("/nonexistent/seq"), DataError, "/nonexistent/seq: no such folder");
}

TEST(KittiSequence, MissingFiles) {
  BINLOOP_REQUIRE_DATA(sample());
  for (const std::string name : {"calib.txt", "times.txt"}) {
    TempDir tmp;
    const auto dir = copySample(tmp);
    fs::remove(dir + "/" + name);
    EXPECT_THROW_WITH(KittiSequence::open(dir), DataError, name + ": no such file");
  }
  TempDir tmp;
  const auto dir = copySample(tmp);
  fs::remove_all(dir + "/image_1");
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError, "image_1: no such folder");
}

TEST(KittiSequence, ShortCalibLine) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  writeText(dir + "/calib.txt",
            "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\nP1: 718.856 0 607.19\n");
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError,
                    "calib.txt:2: P1 (a 3x4 projection matrix) needs 12 numbers, found 3");
}

TEST(KittiSequence, MissingP1) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  writeText(dir + "/calib.txt", "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n");
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError, "calib.txt: no 'P1:' line");
}

TEST(KittiSequence, NonNumericCalib) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  writeText(dir + "/calib.txt",
            "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n"
            "P1: 718.856 0 607.1928 -386.1448 0 7l8.856 185.2157 0 0 0 1 0\n");
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError, "calib.txt:2: '7l8.856' is not a number");
}

TEST(KittiSequence, ImageCountDiffersFromTimes) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  fs::remove(dir + "/image_0/000010.png");
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError,
                    "image_0: holds 10 PNG images but times.txt has 11 lines");
}

TEST(KittiSequence, LeftRightSizeMismatch) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  cv::imwrite(dir + "/image_1/000003.png", cv::Mat(370, 1226, CV_8UC1, cv::Scalar(7)));
  const auto seq = KittiSequence::open(dir);
  EXPECT_THROW_WITH(seq.load(3), DataError, "000003.png: is 1226x370 but its left image is 1241x376");
}

TEST(KittiSequence, UnreadablePng) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  writeText(dir + "/image_0/000005.png", "\x89PNG but then nothing");
  const auto seq = KittiSequence::open(dir);
  EXPECT_THROW_WITH(seq.load(5), DataError, "000005.png: cannot be decoded as an image");
  EXPECT_NO_THROW(seq.load(4));  // one bad frame does not spoil the others
}

TEST(KittiSequence, SixteenBitImageIsRefused) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  cv::imwrite(dir + "/image_0/000002.png", cv::Mat(376, 1241, CV_16UC1, cv::Scalar(700)));
  const auto seq = KittiSequence::open(dir);
  EXPECT_THROW_WITH(seq.load(2), DataError, "000002.png: has 16-bit pixels; expected 8-bit");
}

TEST(KittiSequence, PoseCountMismatch) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto dir = copySample(tmp);
  auto poses = binloop::readKittiPoses(dir + "/poses.txt");
  poses.pop_back();
  binloop::writeKittiPoses(dir + "/poses.txt", poses);
  EXPECT_THROW_WITH(KittiSequence::open(dir), DataError, "has 10 poses but the sequence has 11 frames");
}
