// kitti2bag's writer: the bag read back holds the source pixels and stamps, one message per frame on
// every topic; a bad frame leaves no bag behind.
#include "binloop_ros/kitti_bag_writer.h"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "binloop/io/data_error.h"
#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/stereo_input.h"
#include "binloop_ros/topics.h"
#include "support/test_support.h"

namespace t = binloop_ros::topics;
using binloop::test::TempDir;

namespace {
std::string sample() { return binloop::test::sharedData("kitti/sample_00"); }
}  // namespace

TEST(KittiBagWriter, BagHoldsTheSourceFrames) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto seq = binloop::KittiSequence::open(sample());
  const auto sum = binloop_ros::writeKittiBag(seq, tmp / "s.bag", {});
  EXPECT_EQ(sum.frames, 11u);
  EXPECT_EQ(sum.ground_truth, 11u);

  rosbag::Bag bag(tmp / "s.bag");
  std::map<std::string, int> counts;
  int left_i = 0, right_i = 0, gt_i = 0;
  for (const auto& m : rosbag::View(bag)) {
    ++counts[m.getTopic()];
    if (m.getTopic() == t::kLeftImage || m.getTopic() == t::kRightImage) {
      const bool left = m.getTopic() == t::kLeftImage;
      const int i = left ? left_i++ : right_i++;
      auto img = m.instantiate<sensor_msgs::Image>();
      ASSERT_TRUE(img);
      EXPECT_EQ(img->encoding, "mono8");
      EXPECT_NEAR(img->header.stamp.toSec(), seq.times()[i] + 1.0, 1e-6);
      EXPECT_EQ(img->header.stamp, m.getTime());
      const cv::Mat src = cv::imread(left ? seq.leftPath(i) : seq.rightPath(i), cv::IMREAD_UNCHANGED);
      const cv::Mat got = binloop_ros::toGray(*img);
      ASSERT_EQ(got.size(), src.size());
      EXPECT_EQ(cv::norm(got, src, cv::NORM_INF), 0.0) << "frame " << i;
    } else if (m.getTopic() == t::kRightInfo) {
      auto info = m.instantiate<sensor_msgs::CameraInfo>();
      EXPECT_NEAR(-info->P[3] / info->P[0], 0.537, 0.001);
      EXPECT_EQ(info->width, 1241u);
    } else if (m.getTopic() == t::kGroundTruth) {
      auto odom = m.instantiate<nav_msgs::Odometry>();
      const auto T = binloop_ros::toPose3(odom->pose.pose);
      EXPECT_TRUE(T.isApprox(seq.poses()[gt_i], 1e-6));
      EXPECT_NEAR(odom->header.stamp.toSec(), seq.times()[gt_i] + 1.0, 1e-6);
      ++gt_i;
    }
  }
  EXPECT_EQ(counts[t::kLeftImage], 11);
  EXPECT_EQ(counts[t::kRightImage], 11);
  EXPECT_EQ(counts[t::kLeftInfo], 11);
  EXPECT_EQ(counts[t::kRightInfo], 11);
  EXPECT_EQ(counts[t::kGroundTruth], 11);
}

// --png: the images as image_transport's compressed transport records them, which the Tracking nodelet
// decodes with transport:=compressed back to the same pixels.
TEST(KittiBagWriter, PngImagesDecodeToTheSourcePixels) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto seq = binloop::KittiSequence::open(sample());
  binloop_ros::KittiBagOptions o;
  o.png = true;
  o.end = 2;
  binloop_ros::writeKittiBag(seq, tmp / "p.bag", o);
  rosbag::Bag bag(tmp / "p.bag");
  std::map<std::string, int> counts;
  for (const auto& m : rosbag::View(bag)) {
    ++counts[m.getTopic()];
    if (m.getTopic() != std::string(t::kLeftImage) + "/compressed") continue;
    auto c = m.instantiate<sensor_msgs::CompressedImage>();
    ASSERT_TRUE(c);
    const int i = counts[m.getTopic()] - 1;
    const cv::Mat got = binloop_ros::toGray(*binloop_ros::decompress(*c));
    const cv::Mat src = cv::imread(seq.leftPath(i), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(cv::norm(got, src, cv::NORM_INF), 0.0) << "frame " << i;
  }
  EXPECT_EQ(counts[std::string(t::kLeftImage) + "/compressed"], 3);
  EXPECT_EQ(counts[std::string(t::kRightImage) + "/compressed"], 3);
  EXPECT_EQ(counts[t::kLeftImage], 0);
}

TEST(KittiBagWriter, RangeAndNoOverwrite) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  const auto seq = binloop::KittiSequence::open(sample());
  binloop_ros::KittiBagOptions opt;
  opt.start = 3;
  opt.end = 5;
  EXPECT_EQ(binloop_ros::writeKittiBag(seq, tmp / "r.bag", opt).frames, 3u);
  EXPECT_THROW_WITH(binloop_ros::writeKittiBag(seq, tmp / "r.bag", opt), std::runtime_error,
                    "already exists (use --force to overwrite)");
  opt.overwrite = true;
  opt.start = 20;
  EXPECT_THROW_WITH(binloop_ros::writeKittiBag(seq, tmp / "r.bag", opt), std::runtime_error,
                    "past the sequence end");
}

TEST(KittiBagWriter, CorruptFrameLeavesNoBag) {
  BINLOOP_REQUIRE_DATA(sample());
  TempDir tmp;
  binloop::test::copyTree(sample(), tmp / "seq");
  binloop::test::writeText(tmp / "seq/image_1/000007.png", "garbage");
  const auto seq = binloop::KittiSequence::open(tmp / "seq");
  EXPECT_THROW_WITH(binloop_ros::writeKittiBag(seq, tmp / "c.bag", {}), binloop::DataError,
                    "000007.png: cannot be decoded");
  EXPECT_FALSE(std::filesystem::exists(tmp / "c.bag"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "c.bag.partial"));
}
