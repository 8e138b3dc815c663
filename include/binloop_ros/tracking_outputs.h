#pragma once
// What the Tracking nodelet publishes for a tracked pair: the keyframe to local mapping, the tracked frame,
// the camera's pose and the live path in the slam frame, odometry and tf (FramePublisher), and the debug
// image (drawn only while someone subscribes).
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <opencv2/core.hpp>

#include <memory>
#include <string>

#include "binloop/messages/keyframe.h"
#include "binloop/messages/tracked_frame.h"
#include "binloop/tracking/frame.h"
#include "binloop/tracking/tracking_stage.h"
#include "binloop_ros/frame_publisher.h"

namespace binloop_ros {

class TrackingOutputs {
 public:
  /// Advertises on `nh`; FramePublisher reads its parameters from `pnh` (and throws for a malformed one).
  TrackingOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, size_t path_max_poses);

  FramePublisher& frames() { return *frames_; }
  const std::string& slamFrame() const { return frames_->slamFrame(); }
  bool keyframesHeard() const { return keyframe_pub_.getNumSubscribers() > 0; }

  void keyframe(const binloop::msg::KeyFrame& k);
  /// The keyframes a restarted local mapping lacks (TrackingStage::takeResend), once it listens; says so.
  void resendKeyframes(binloop::TrackingStage& stage);
  /// The tracked frame, and for a tracked one its pose, odometry, tf and live path (a lost one keeps
  /// map -> odom alive). `corrections`: the loop corrections applied so far (when it moved since the last
  /// pose, the slam-frame pose may jump and odometry must not). Returns tf's problem, "" if none.
  std::string frame(const binloop::msg::TrackedFrame& f, const std_msgs::Header& header,
                    uint64_t corrections);
  /// The left image with the features of `last` (the tracker's last frame, when it is `f`'s).
  void debugImage(const cv::Mat& gray, const binloop::Frame* last, const binloop::msg::TrackedFrame& f,
                  const std_msgs::Header& header);

  /// A reset or a loaded map: odometry starts over, the live path is cleared.
  void restart();
  /// The images' clock went back (a replayed bag).
  void clockWentBack();

 private:
  std::unique_ptr<FramePublisher> frames_;
  ros::Publisher keyframe_pub_, frame_pub_, pose_pub_, path_pub_, debug_pub_;
  nav_msgs::Path path_;
  size_t path_max_poses_;
  uint64_t corrections_at_last_ = 0;
};

}  // namespace binloop_ros
