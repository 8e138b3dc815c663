#pragma once
// Where the Tracking nodelet's stereo pairs wait and are checked before the tracker sees them: the
// camera_info pair, the queue of pairs waiting for the first camera_info or (in lock-step) for local mapping,
// and the checks of a pair (left/right stamps and sizes, the stamp against the clock so far).
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "binloop/types/stereo_camera.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/stamp_gate.h"
#include "binloop_ros/topics.h"

namespace binloop_ros {

class PairIntake {
 public:
  using Pair = std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::ImageConstPtr>;

  PairIntake(const topics::StereoTopics& in, double max_stamp_diff, bool lockstep, StampGateParams stamps)
      : in_(in), max_stamp_diff_(max_stamp_diff), lockstep_(lockstep), stamps_(stamps) {}

  /// Subscribes to the two camera_info topics; `on_info` runs (guarded) after each one is taken.
  void subscribeInfo(ros::NodeHandle& nh, CallbackGuard& guard, std::function<void()> on_info);
  void info(const sensor_msgs::CameraInfoConstPtr& m, bool right) { (right ? right_info_ : left_info_) = m; }
  bool hasInfo() const { return left_info_ && right_info_; }
  /// The camera of the camera_info pair (throws ConversionError for an unusable one) and a note on its
  /// distortion ("" if none).
  binloop::StereoCamera camera() const;
  std::string distortion() const;
  /// An unusable camera_info pair: the next one is waited for.
  void forgetInfo() { left_info_.reset(); }
  /// Why no camera is known yet.
  std::string noInfo() const;

  /// Queues the pair when it must wait: no camera yet (`has_camera` false) or, in lock-step, keyframes in
  /// flight or pairs ahead of it. A full queue drops its oldest pair and says why in `dropped`. False: track
  /// it now.
  bool hold(const Pair& p, bool has_camera, size_t in_flight, std::string* dropped);
  /// The next waiting pair that may be tracked now.
  std::optional<Pair> next(bool has_camera, size_t in_flight);
  size_t waiting() const { return waiting_.size(); }

  /// What is wrong with the pair as a pair (stamps apart, sizes that differ), "" if nothing.
  std::string pairProblem(const sensor_msgs::Image& left, const sensor_msgs::Image& right);
  /// An image of another size than the camera's, "" if it fits.
  static std::string sizeProblem(const sensor_msgs::Image& left, const binloop::StereoCamera& cam);
  double lastStampDiff() const { return last_stamp_diff_; }
  /// The stamp against the clock so far (counts the pairs it takes; call last).
  StampGate::Decision stamp(const ros::Time& t) { return stamps_.check(t.toSec()); }
  /// A reset or a loaded map: the clock starts again.
  void restart() { stamps_.reset(); }

 private:
  topics::StereoTopics in_;
  double max_stamp_diff_;
  bool lockstep_;
  StampGate stamps_;
  sensor_msgs::CameraInfoConstPtr left_info_, right_info_;
  ros::Subscriber left_info_sub_, right_info_sub_;
  std::deque<Pair> waiting_;
  size_t max_waiting_ = 100;  // lock-step pairs held for mapping at most (the oldest are dropped)
  double last_stamp_diff_ = 0;
};

}  // namespace binloop_ros
