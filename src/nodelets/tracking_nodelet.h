#pragma once
// binloop/Tracking, the nodelet: stereo images in, the camera's pose out (pose, odometry, path, tf),
// keyframes to local mapping; local mapping's updates back in. It wires ROS to binloop::TrackingStage (the
// tracker, its map's lifecycle and the keyframes in flight, without ROS) through adapters of their own: the
// parameters (tracking_params.h), the pairs' checks and queue (pair_intake.h), what is published
// (tracking_outputs.h), the counts and diagnostics (tracking_status.h) and the map services
// (tracking_services.h). Every callback runs through one CallbackGuard: a bad message is reported (log +
// diagnostics) and dropped, and the nodelet goes on.
#include <binloop/LocalMapUpdate.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nodelet/nodelet.h>

#include <memory>

#include "binloop/tracking/tracking_stage.h"
#include "binloop_ros/callback_guard.h"
#include "binloop_ros/cpu_meter.h"
#include "binloop_ros/pair_intake.h"
#include "binloop_ros/stage_diagnostics.h"
#include "binloop_ros/stereo_input.h"
#include "binloop_ros/tracking_outputs.h"
#include "binloop_ros/tracking_params.h"
#include "binloop_ros/tracking_services.h"
#include "binloop_ros/tracking_status.h"

namespace binloop_ros {

using sensor_msgs::ImageConstPtr;

class TrackingNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  /// A synchronised pair: tracked now, or queued (no camera yet; lock-step while mapping works).
  void onImages(const ImageConstPtr& left, const ImageConstPtr& right);
  /// Why the pair cannot be tracked ("" if it can); makes the tracker once camera_info is known.
  std::string check(const sensor_msgs::Image& left, const sensor_msgs::Image& right);
  void track(const ImageConstPtr& left, const ImageConstPtr& right);
  void trackWaiting();
  bool hasCamera() const { return stage_->tracker() || intake_->hasInfo(); }
  void onUpdate(const binloop::LocalMapUpdateConstPtr& u);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStampedConstPtr& m);
  void reject(const std::string& why);
  void problem(const std::string& why);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& s);
  /// The stage's tracker was replaced (a loaded map, a reset, local mapping's map): what the nodelet kept
  /// of the old tracker's frames goes.
  void startedOver();
  void adopted(binloop::TrackingStage::Adopted how);

  TrackingParams p_;
  CallbackGuard guard_{"Tracking"};
  std::unique_ptr<binloop::TrackingStage> stage_;
  std::unique_ptr<PairIntake> intake_;
  std::unique_ptr<TrackingOutputs> out_;
  std::unique_ptr<StereoInput> input_;
  std::unique_ptr<StageServices> services_;
  std::unique_ptr<StageDiagnostics> diag_;
  ros::Subscriber update_sub_, initial_pose_sub_;
  CpuMeter cpu_;
  ros::WallTime last_pair_wall_;  // no pair for ~stale_after_s: WARN
  TrackingStatus st_;
};

}  // namespace binloop_ros
