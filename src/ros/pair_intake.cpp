#include "binloop_ros/pair_intake.h"

#include "binloop_ros/msg_conversion.h"

namespace binloop_ros {

void PairIntake::subscribeInfo(ros::NodeHandle& nh, CallbackGuard& guard, std::function<void()> on_info) {
  for (const bool right : {false, true})
    (right ? right_info_sub_ : left_info_sub_) = nh.subscribe<sensor_msgs::CameraInfo>(
        right ? in_.right_info : in_.left_info, 2,
        guard.wrap(right ? "right camera_info" : "left camera_info",
                   [this, right, on_info](const sensor_msgs::CameraInfoConstPtr& m) {
                     info(m, right);
                     on_info();
                   }));
}

binloop::StereoCamera PairIntake::camera() const { return toStereoCamera(*left_info_, *right_info_); }

std::string PairIntake::distortion() const { return distortionWarning(*left_info_); }

std::string PairIntake::noInfo() const {
  return std::string("no camera_info received yet on ") + (left_info_ ? in_.right_info : in_.left_info) +
         " (or give ~camera)";
}

bool PairIntake::hold(const Pair& p, bool has_camera, size_t in_flight, std::string* dropped) {
  if (has_camera && !(lockstep_ && (in_flight > 0 || !waiting_.empty()))) return false;
  waiting_.push_back(p);
  if (!has_camera && waiting_.size() > 10) {
    waiting_.pop_front();
    *dropped = noInfo();
  } else if (waiting_.size() > max_waiting_) {
    waiting_.pop_front();
    *dropped = "lock-step: " + std::to_string(max_waiting_) +
               " pairs already wait for local mapping; the oldest is dropped";
  }
  return true;
}

std::optional<PairIntake::Pair> PairIntake::next(bool has_camera, size_t in_flight) {
  if (waiting_.empty() || !has_camera || (lockstep_ && in_flight > 0)) return std::nullopt;
  Pair p = waiting_.front();
  waiting_.pop_front();
  return p;
}

std::string PairIntake::pairProblem(const sensor_msgs::Image& left, const sensor_msgs::Image& right) {
  last_stamp_diff_ = std::abs((left.header.stamp - right.header.stamp).toSec());
  if (last_stamp_diff_ > max_stamp_diff_)
    return "left and right stamps differ by " + std::to_string(last_stamp_diff_) +
           " s (more than ~max_stamp_diff " + std::to_string(max_stamp_diff_) +
           " s): not a synchronised pair";
  if (left.width != right.width || left.height != right.height)
    return "left is " + std::to_string(left.width) + "x" + std::to_string(left.height) + ", right " +
           std::to_string(right.width) + "x" + std::to_string(right.height);
  return "";
}

std::string PairIntake::sizeProblem(const sensor_msgs::Image& left, const binloop::StereoCamera& cam) {
  if (static_cast<int>(left.width) == cam.width && static_cast<int>(left.height) == cam.height) return "";
  return "image is " + std::to_string(left.width) + "x" + std::to_string(left.height) + ", the camera " +
         std::to_string(cam.width) + "x" + std::to_string(cam.height);
}

}  // namespace binloop_ros
