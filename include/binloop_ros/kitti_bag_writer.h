#pragma once
// Writes a KITTI sequence as a ROS 1 bag: mono8 left/right images (or PNG-compressed ones) and CameraInfo
// with identical stamps, and ground truth as nav_msgs/Odometry when the sequence has poses.
#include <functional>
#include <limits>
#include <string>

#include "binloop/io/kitti_sequence.h"

namespace binloop_ros {

struct KittiBagOptions {
  size_t start = 0;                                 // first frame (inclusive)
  size_t end = std::numeric_limits<size_t>::max();  // last frame (inclusive), clipped to the sequence
  double stamp_offset_s = 1.0;  // stamp = times.txt + offset; ROS forbids time 0, where KITTI starts
  bool lz4 = false;             // compress chunks
  bool png = false;             // images as PNG sensor_msgs/CompressedImage on <image topic>/compressed, as
                                // image_transport's compressed transport records them (lossless)
  bool overwrite = false;       // refuse an existing output file unless set
};

struct KittiBagSummary {
  size_t frames = 0;
  size_t ground_truth = 0;
  double first_stamp = 0, last_stamp = 0;
  size_t bytes = 0;
};

/// Writes to `<out>.partial` and renames at the end, so a failure never leaves a half-written bag under the
/// requested name. Throws binloop::DataError for input problems and std::runtime_error for output ones.
KittiBagSummary writeKittiBag(const binloop::KittiSequence& seq, const std::string& out,
                              const KittiBagOptions& opt,
                              const std::function<void(size_t done, size_t total)>& progress = {});

}  // namespace binloop_ros
