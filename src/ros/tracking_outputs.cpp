#include "binloop_ros/tracking_outputs.h"

#include <geometry_msgs/PoseStamped.h>
#include <sensor_msgs/Image.h>
#include <opencv2/imgproc.hpp>

#include <binloop/KeyFrame.h>
#include <binloop/TrackedFrame.h>

#include "binloop_ros/msg_conversion.h"
#include "binloop_ros/stage_msg_conversion.h"

namespace binloop_ros {

TrackingOutputs::TrackingOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, size_t path_max_poses)
    : frames_(std::make_unique<FramePublisher>(nh, pnh)), path_max_poses_(path_max_poses) {
  // Room for a whole resend (TrackingStage::takeResend), which goes out at once.
  keyframe_pub_ = nh.advertise<binloop::KeyFrame>("keyframe", binloop::TrackingStage::kResendWindow + 10);
  frame_pub_ = nh.advertise<binloop::TrackedFrame>("tracked_frame", 100);
  pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  path_pub_ = nh.advertise<nav_msgs::Path>("live_path", 1, true);
  debug_pub_ = nh.advertise<sensor_msgs::Image>("debug_image", 1);
}

void TrackingOutputs::keyframe(const binloop::msg::KeyFrame& k) {
  keyframe_pub_.publish(boost::make_shared<binloop::KeyFrame>(toRos(k, slamFrame())));
}

void TrackingOutputs::resendKeyframes(binloop::TrackingStage& stage) {
  if (!stage.resendPending() || !keyframesHeard()) return;
  uint64_t lost = 0;
  const std::vector<binloop::msg::KeyFramePtr> again = stage.takeResend(ros::WallTime::now().toSec(), &lost);
  for (const binloop::msg::KeyFramePtr& k : again) keyframe(*k);
  ROS_WARN(
      "binloop/Tracking: local mapping restarted without the last %zu keyframes: sent again (%lu older "
      "ones no longer kept)",
      again.size(), static_cast<unsigned long>(lost));
}

std::string TrackingOutputs::frame(const binloop::msg::TrackedFrame& f, const std_msgs::Header& header,
                                   uint64_t corrections) {
  frame_pub_.publish(boost::make_shared<binloop::TrackedFrame>(toRos(f, slamFrame())));
  using binloop::msg::TrackingState;
  if (f.state == TrackingState::kNotInitialized || f.state == TrackingState::kLost) {
    frames_->lost(header.stamp);
    return "";
  }
  frames_->tracked(f.T_w_c, f.pose_covariance, header.stamp, header.frame_id,
                   corrections != corrections_at_last_);
  corrections_at_last_ = corrections;

  // The camera's pose in the slam frame, as the SLAM's other outputs.
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = header.stamp;
  pose.header.frame_id = slamFrame();
  pose.pose = toPoseMsg(f.T_w_c);
  pose_pub_.publish(pose);

  // The live path: the last ~path_max_poses poses, serialised only for a subscriber (a whole drive's path
  // grew by a pose a frame and was re-sent every frame).
  path_.header = pose.header;
  path_.poses.push_back(pose);
  if (path_.poses.size() > path_max_poses_)
    path_.poses.erase(path_.poses.begin(),
                      path_.poses.begin() + static_cast<long>(path_.poses.size() - path_max_poses_));
  if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(path_);
  return frames_->takeProblem();
}

// Green tracked (matched to a map point and an inlier), orange matched but rejected as an outlier, blue with
// a stereo match only, grey the rest; the state and counts on top.
void TrackingOutputs::debugImage(const cv::Mat& gray, const binloop::Frame* last,
                                 const binloop::msg::TrackedFrame& f, const std_msgs::Header& header) {
  if (debug_pub_.getNumSubscribers() == 0) return;
  cv::Mat img;
  cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  if (last && last->index == f.frame_index) {
    for (size_t i = 0; i < last->size(); ++i) {
      const auto& k = last->keypoints[i];
      cv::Scalar colour(150, 150, 150);
      if (last->points[i] != binloop::kNoId)
        colour = last->outlier[i] ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 220, 0);
      else if (k.right_x >= 0)
        colour = cv::Scalar(255, 120, 0);
      cv::circle(img, cv::Point2f(k.x, k.y), 2 + k.octave, colour, 1, cv::LINE_AA);
    }
  }
  const std::string text = std::string(binloop::msg::toString(f.state)) + "  features " +
                           std::to_string(f.features) + "  stereo " + std::to_string(f.stereo_matches) +
                           "  tracked " + std::to_string(f.tracked_points);
  cv::putText(img, text, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(0, 255, 255), 2,
              cv::LINE_AA);
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->height = img.rows;
  msg->width = img.cols;
  msg->encoding = "bgr8";
  msg->step = img.cols * 3;
  msg->data.assign(img.data, img.data + img.total() * 3);
  debug_pub_.publish(msg);
}

void TrackingOutputs::restart() {
  frames_->restart();
  path_.poses.clear();
}

void TrackingOutputs::clockWentBack() {
  frames_->clockWentBack();
  path_.poses.clear();
}

}  // namespace binloop_ros
