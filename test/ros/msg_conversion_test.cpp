#include "binloop_ros/msg_conversion.h"

#include <opencv2/core.hpp>

#include "support/test_support.h"

using binloop_ros::ConversionError;

TEST(MsgConversion, ImageRoundTripAndColour) {
  cv::Mat gray(4, 5, CV_8UC1);
  for (int i = 0; i < 20; ++i) gray.data[i] = static_cast<uint8_t>(10 * i);
  const auto msg = binloop_ros::toImageMsg(gray, ros::Time(2.0), "cam");
  EXPECT_EQ(msg.encoding, "mono8");
  EXPECT_EQ(cv::norm(binloop_ros::toGray(msg), gray, cv::NORM_INF), 0.0);

  sensor_msgs::Image rgb;
  rgb.encoding = "rgb8";
  rgb.width = 1;
  rgb.height = 1;
  rgb.step = 3;
  rgb.data = {255, 0, 0};                                          // pure red
  EXPECT_NEAR(binloop_ros::toGray(rgb).at<uint8_t>(0, 0), 76, 1);  // 0.299 * 255
}

TEST(MsgConversion, BadImagesAreRefusedWithAReason) {
  sensor_msgs::Image m;
  m.encoding = "mono16";
  m.width = m.height = 2;
  m.step = 4;
  m.data.resize(8);
  EXPECT_THROW_WITH(binloop_ros::toGray(m), ConversionError, "image encoding 'mono16' is not supported");
  m.encoding = "mono8";
  m.step = 2;
  m.data.resize(3);
  EXPECT_THROW_WITH(binloop_ros::toGray(m), ConversionError,
                    "image data holds 3 bytes, expected step x height = 4");
  m.step = 1;
  EXPECT_THROW_WITH(binloop_ros::toGray(m), ConversionError, "step 1 is less than width");
}

TEST(MsgConversion, CameraInfoPairRoundTrip) {
  const auto cam = binloop::kitti00Camera();
  const auto l = binloop_ros::toCameraInfo(cam, false, ros::Time(1), "l");
  const auto r = binloop_ros::toCameraInfo(cam, true, ros::Time(1), "r");
  EXPECT_EQ(binloop_ros::toStereoCamera(l, r), cam);
  auto r_bad = r;
  r_bad.P[2] += 3;
  EXPECT_THROW_WITH(binloop_ros::toStereoCamera(l, r_bad), ConversionError, "not a rectified pair");
  EXPECT_THROW_WITH(binloop_ros::toStereoCamera(l, l), ConversionError, "must be -fx*baseline");
}

// image_proc passes the raw camera's distortion on with image_rect: binloop says what it assumes.
TEST(MsgConversion, DistortionInCameraInfoIsNamedInAWarning) {
  auto info = binloop_ros::toCameraInfo(binloop::kitti00Camera(), false, ros::Time(1), "cam");
  EXPECT_EQ(binloop_ros::distortionWarning(info), "");
  info.D = {-0.28, 0.07, 0, 0, 0};
  const std::string w = binloop_ros::distortionWarning(info);
  EXPECT_NE(w.find("camera_info of 'cam' has distortion (plumb_bob D = [-0.280000, 0.070000, 0.000000"),
            std::string::npos)
      << w;
  EXPECT_NE(w.find("takes the images as rectified (image_rect)"), std::string::npos) << w;
}

TEST(MsgConversion, PoseRoundTrip) {
  binloop::Pose3 T = binloop::Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() << 1, 2, 3;
  EXPECT_TRUE(binloop_ros::toPose3(binloop_ros::toPoseMsg(T)).isApprox(T, 1e-12));
  EXPECT_THROW_WITH(binloop_ros::toRosTime(0.0), ConversionError, "outside ROS's range");
}
