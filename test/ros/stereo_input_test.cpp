// Compressed stereo input: what image_transport's compressed transport (and bags of it) carry, decoded to
// the Images the tracker takes, and one clear reason for bytes that are not an image.
#include "binloop_ros/stereo_input.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop_ros/msg_conversion.h"
#include "support/test_support.h"

using binloop_ros::decompress;

namespace {

sensor_msgs::CompressedImage compressed(const cv::Mat& img, const std::string& ext,
                                        const std::string& format) {
  sensor_msgs::CompressedImage m;
  m.header.stamp = ros::Time(12.5);
  m.header.frame_id = "cam";
  m.format = format;
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, img, bytes));
  m.data = bytes;
  return m;
}

cv::Mat gradient(int type) {
  cv::Mat img(48, 64, type);
  img.forEach<uint8_t>([](uint8_t& v, const int* p) { v = static_cast<uint8_t>(p[0] * 3 + p[1]); });
  return img;
}

}  // namespace

TEST(StereoInput, PngAndJpegDecodeToGreyImagesWithTheirHeader) {
  const cv::Mat grey = gradient(CV_8UC1);
  const auto png = decompress(compressed(grey, ".png", "mono8; png compressed "));
  EXPECT_EQ(png->encoding, "mono8");
  EXPECT_EQ(png->width, 64u);
  EXPECT_EQ(png->height, 48u);
  EXPECT_EQ(png->header.frame_id, "cam");
  EXPECT_EQ(png->header.stamp, ros::Time(12.5));
  EXPECT_EQ(0, std::memcmp(png->data.data(), grey.data, grey.total()));  // lossless
  const auto jpeg = decompress(compressed(grey, ".jpg", "jpeg"));
  EXPECT_EQ(jpeg->encoding, "mono8");
  cv::Mat colour;
  cv::cvtColor(grey, colour, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(decompress(compressed(colour, ".jpg", "bgr8; jpeg compressed bgr8"))->encoding, "bgr8");
}

TEST(StereoInput, BytesThatAreNotAnImageGiveTheReason) {
  auto m = compressed(gradient(CV_8UC1), ".png", "png");
  m.format = "theora";
  EXPECT_THROW_WITH(decompress(m), binloop_ros::ConversionError,
                    "format 'theora': only jpeg and png are decoded");
  m.format = "png";
  m.data.resize(m.data.size() / 3);
  EXPECT_THROW_WITH(decompress(m), binloop_ros::ConversionError, "does not decode");
  m.data.clear();
  EXPECT_THROW_WITH(decompress(m), binloop_ros::ConversionError, "no bytes");
  cv::Mat deep(8, 8, CV_16UC1, cv::Scalar(1000));
  EXPECT_THROW_WITH(decompress(compressed(deep, ".png", "png")), binloop_ros::ConversionError,
                    "expected 8-bit");
}
