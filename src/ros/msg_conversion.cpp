#include "binloop_ros/msg_conversion.h"

#include <cmath>

#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

namespace binloop_ros {

namespace enc = sensor_msgs::image_encodings;

sensor_msgs::Image toImageMsg(const cv::Mat& gray, const ros::Time& stamp, const std::string& frame_id) {
  if (gray.type() != CV_8UC1) throw ConversionError("toImageMsg: expected an 8-bit grey image");
  sensor_msgs::Image msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  msg.height = gray.rows;
  msg.width = gray.cols;
  msg.encoding = enc::MONO8;
  msg.is_bigendian = 0;
  msg.step = gray.cols;
  msg.data.resize(static_cast<size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r) std::copy_n(gray.ptr<uint8_t>(r), gray.cols, &msg.data[r * msg.step]);
  return msg;
}

cv::Mat toGray(const sensor_msgs::Image& msg) {
  struct Fmt {
    const char* name;
    int type;
    int code;  // -1: no conversion
  };
  static const Fmt kFormats[] = {{"mono8", CV_8UC1, -1},
                                 {"bgr8", CV_8UC3, cv::COLOR_BGR2GRAY},
                                 {"rgb8", CV_8UC3, cv::COLOR_RGB2GRAY},
                                 {"bgra8", CV_8UC4, cv::COLOR_BGRA2GRAY},
                                 {"rgba8", CV_8UC4, cv::COLOR_RGBA2GRAY}};
  const Fmt* fmt = nullptr;
  for (const auto& f : kFormats)
    if (msg.encoding == f.name) fmt = &f;
  if (!fmt)
    throw ConversionError("image encoding '" + msg.encoding +
                          "' is not supported; publish mono8 (or bgr8/rgb8/bgra8/rgba8) rectified images");
  const size_t pixel_bytes = CV_ELEM_SIZE(fmt->type);
  if (msg.width == 0 || msg.height == 0) throw ConversionError("image has zero width or height");
  if (msg.step < msg.width * pixel_bytes)
    throw ConversionError("image step " + std::to_string(msg.step) + " is less than width x pixel size " +
                          std::to_string(msg.width * pixel_bytes));
  if (msg.data.size() < static_cast<size_t>(msg.step) * msg.height)
    throw ConversionError(
        "image data holds " + std::to_string(msg.data.size()) +
        " bytes, expected step x height = " + std::to_string(static_cast<size_t>(msg.step) * msg.height));
  const cv::Mat view(msg.height, msg.width, fmt->type, const_cast<uint8_t*>(msg.data.data()), msg.step);
  cv::Mat gray;
  if (fmt->code < 0) {
    view.copyTo(gray);
  } else {
    cv::cvtColor(view, gray, fmt->code);
  }
  return gray;
}

sensor_msgs::CameraInfo toCameraInfo(const binloop::StereoCamera& cam, bool right, const ros::Time& stamp,
                                     const std::string& frame_id) {
  sensor_msgs::CameraInfo info;
  info.header.stamp = stamp;
  info.header.frame_id = frame_id;
  info.width = cam.width;
  info.height = cam.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);  // images are rectified
  info.K = {cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const auto P = cam.projectionMatrix(right);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) info.P[r * 4 + c] = P(r, c);
  return info;
}

std::string distortionWarning(const sensor_msgs::CameraInfo& info) {
  bool distorted = false;
  std::string d;
  for (double v : info.D) {
    distorted = distorted || v != 0;
    d += (d.empty() ? "" : ", ") + std::to_string(v);
  }
  if (!distorted) return "";
  return "camera_info of '" + info.header.frame_id + "' has distortion (" + info.distortion_model + " D = [" +
         d +
         "]): binloop uses only its P and takes the images as rectified (image_rect); raw, distorted images "
         "would "
         "give wrong poses";
}

binloop::StereoCamera toStereoCamera(const sensor_msgs::CameraInfo& left,
                                     const sensor_msgs::CameraInfo& right) {
  if (left.width != right.width || left.height != right.height)
    throw ConversionError("left and right camera_info sizes differ");
  for (int i : {0, 2, 5, 6})
    if (std::abs(left.P[i] - right.P[i]) > 1e-6 * std::max(1.0, std::abs(left.P[i])))
      throw ConversionError(
          "left and right camera_info P differ in fx/fy/cx/cy: images are not a rectified pair");
  if (left.P[0] <= 0 || left.P[5] <= 0)
    throw ConversionError("camera_info P has a non-positive focal length");
  if (right.P[3] >= 0)
    throw ConversionError("right camera_info P[3] must be -fx*baseline (negative); got " +
                          std::to_string(right.P[3]));
  binloop::StereoCamera cam;
  cam.fx = left.P[0];
  cam.cx = left.P[2];
  cam.fy = left.P[5];
  cam.cy = left.P[6];
  cam.baseline_m = -(right.P[3] - left.P[3]) / right.P[0];
  cam.width = static_cast<int>(left.width);
  cam.height = static_cast<int>(left.height);
  return cam;
}

geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

CovarianceMsg toCovarianceMsg(const binloop::Matrix6d& c) {
  CovarianceMsg m;
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) m[6 * r + k] = c(r, k);
  return m;
}

binloop::Matrix6d fromCovarianceMsg(const CovarianceMsg& m) {
  binloop::Matrix6d c;
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) c(r, k) = m[6 * r + k];
  return c;
}

geometry_msgs::Pose toPoseMsg(const binloop::Pose3& T) {
  geometry_msgs::Pose p;
  const Eigen::Quaterniond q(T.rotation());
  p.position.x = T.translation().x();
  p.position.y = T.translation().y();
  p.position.z = T.translation().z();
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

binloop::Pose3 toPose3(const geometry_msgs::Pose& msg) {
  for (double v : {msg.position.x, msg.position.y, msg.position.z, msg.orientation.x, msg.orientation.y,
                   msg.orientation.z, msg.orientation.w})
    if (!std::isfinite(v)) throw ConversionError("pose has a NaN or infinite number");
  Eigen::Quaterniond q(msg.orientation.w, msg.orientation.x, msg.orientation.y, msg.orientation.z);
  if (q.norm() < 1e-6) throw ConversionError("pose orientation is a zero quaternion");
  binloop::Pose3 T = binloop::Pose3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(msg.position.x, msg.position.y, msg.position.z);
  return T;
}

geometry_msgs::TransformStamped toTransformMsg(const binloop::Pose3& T, const ros::Time& stamp,
                                               const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  const geometry_msgs::Pose p = toPoseMsg(T);
  t.transform.translation.x = p.position.x;
  t.transform.translation.y = p.position.y;
  t.transform.translation.z = p.position.z;
  t.transform.rotation = p.orientation;
  return t;
}

binloop::Pose3 toPose3(const geometry_msgs::Transform& t) {
  geometry_msgs::Pose p;
  p.position.x = t.translation.x;
  p.position.y = t.translation.y;
  p.position.z = t.translation.z;
  p.orientation = t.rotation;
  return toPose3(p);
}

ros::Time toRosTime(double seconds) {
  if (!(seconds > 0) || seconds > 4294967295.0)
    throw ConversionError("time " + std::to_string(seconds) + " s is outside ROS's range (0, 2^32) s");
  return ros::Time(seconds);
}

}  // namespace binloop_ros
