#pragma once
#include <string>

// Default topic and frame names, shared by kitti2bag, the launch files and the nodelets, so a bag made by
// one plays into the other without remapping. Layout follows stereo_image_proc (<ns>/left/image_rect).
namespace binloop_ros::topics {

constexpr const char* kLeftImage = "/stereo/left/image_rect";
constexpr const char* kLeftInfo = "/stereo/left/camera_info";
constexpr const char* kRightImage = "/stereo/right/image_rect";
constexpr const char* kRightInfo = "/stereo/right/camera_info";
constexpr const char* kGroundTruth = "/ground_truth/odom";

/// The Tracking nodelet's inputs under its `~stereo` namespace (default "/stereo", the topics above):
/// <ns>/left/image_rect, <ns>/left/camera_info, <ns>/right/...; a relative namespace resolves in the
/// nodelet's own.
constexpr const char* kStereoNamespace = "/stereo";
struct StereoTopics {
  std::string left_image, left_info, right_image, right_info;
  explicit StereoTopics(const std::string& ns)
      : left_image(ns + "/left/image_rect"),
        left_info(ns + "/left/camera_info"),
        right_image(ns + "/right/image_rect"),
        right_info(ns + "/right/camera_info") {}
};

constexpr const char* kLeftFrame = "stereo_left_optical_frame";
constexpr const char* kRightFrame = "stereo_right_optical_frame";
/// KITTI's ground-truth world: camera 0's optical frame at the first frame (z forward, y down).
constexpr const char* kGroundTruthFrame = "world";

}  // namespace binloop_ros::topics
