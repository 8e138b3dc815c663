#pragma once
// Every conversion between ROS messages and core types lives here (and is tested in
// test/ros/msg_conversion_test.cpp), so the rest of the ROS layer never touches message fields.
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <opencv2/core/mat.hpp>
#include <stdexcept>
#include <string>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop_ros {

/// Thrown for a message that cannot be converted; the text says which field and why.
class ConversionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Copies an 8-bit grey image into a mono8 message.
sensor_msgs::Image toImageMsg(const cv::Mat& gray, const ros::Time& stamp, const std::string& frame_id);
/// mono8 is taken as is; bgr8/rgb8/bgra8/rgba8 are converted to grey. Anything else (16-bit, Bayer,
/// float) or a message whose step or data size disagrees with its width/height throws ConversionError.
cv::Mat toGray(const sensor_msgs::Image& msg);

/// CameraInfo of a rectified stereo camera (D empty-zero, R identity, P with Tx = -fx·b for the right).
sensor_msgs::CameraInfo toCameraInfo(const binloop::StereoCamera& cam, bool right, const ros::Time& stamp,
                                     const std::string& frame_id);
/// Builds the stereo camera from a left/right CameraInfo pair; throws ConversionError when they are not
/// a rectified pair (different intrinsics or sizes, right Tx not negative).
binloop::StereoCamera toStereoCamera(const sensor_msgs::CameraInfo& left,
                                     const sensor_msgs::CameraInfo& right);
/// "" when `info` has no distortion, else a warning that says what binloop assumes: camera_info for
/// image_rect carries the raw camera's D (image_proc passes it on), and binloop uses only P, which is right
/// for rectified images and wrong for raw ones.
std::string distortionWarning(const sensor_msgs::CameraInfo& info);

geometry_msgs::Pose toPoseMsg(const binloop::Pose3& T);
/// A 6x6 covariance as ROS messages carry it (36 numbers, row-major), and back.
using CovarianceMsg = geometry_msgs::PoseWithCovariance::_covariance_type;  // 36 numbers, row-major
CovarianceMsg toCovarianceMsg(const binloop::Matrix6d& c);
binloop::Matrix6d fromCovarianceMsg(const CovarianceMsg& m);
geometry_msgs::Point toPoint(const Eigen::Vector3d& p);
binloop::Pose3 toPose3(const geometry_msgs::Pose& msg);
/// tf's form of the same: `T` as the transform from `parent` to `child` (child's pose in parent).
geometry_msgs::TransformStamped toTransformMsg(const binloop::Pose3& T, const ros::Time& stamp,
                                               const std::string& parent, const std::string& child);
/// Throws ConversionError as toPose3 does.
binloop::Pose3 toPose3(const geometry_msgs::Transform& t);

/// Seconds from the start of a sequence to a ROS stamp; throws ConversionError outside ROS's range.
ros::Time toRosTime(double seconds);

}  // namespace binloop_ros
