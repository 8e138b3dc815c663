#pragma once
// The Tracking nodelet's parameters (docs/ros.md lists them), read and checked in one place: an unknown name,
// a bad value or an unusable relocalisation vocabulary throws with the reason, before anything is advertised.
#include <ros/ros.h>

#include <optional>
#include <string>

#include "binloop/pipeline/slam_config.h"
#include "binloop/types/stereo_camera.h"
#include "binloop_ros/stamp_gate.h"

namespace binloop_ros {

struct TrackingParams {
  binloop::SlamConfig config;  // ~config, ~seed, ~localize_only, ~reloc_vocab
  std::optional<binloop::StereoCamera>
      camera;                // ~camera/{fx,fy,cx,cy,baseline,width,height}: instead of camera_info
  std::string camera_frame;  // ~camera_frame; "": the left image's frame_id
  std::string stereo;        // ~stereo: the input topics' namespace
  std::string transport = "raw", sync = "exact";
  int queue_size = 5;
  double max_stamp_diff = 0.002;  // s between left and right
  StampGateParams stamps;         // ~max_time_jump, ~time_jump_confirm_pairs
  double keyframe_timeout_s = 5;
  double stale_after_s = 2;
  size_t path_max_poses = 1000;
  bool lockstep = false;

  /// Throws for an unknown parameter, a value out of range or a relocalisation vocabulary that cannot be used
  /// (a bad ~camera is refused when the tracker is made of it).
  static TrackingParams read(const ros::NodeHandle& pnh);
};

}  // namespace binloop_ros
