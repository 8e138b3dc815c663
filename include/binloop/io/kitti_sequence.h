#pragma once
// A KITTI odometry sequence folder: image_0/ and image_1/ (rectified left/right PNGs, one per line of
// times.txt), calib.txt, times.txt, and optionally poses.txt (ground truth, T_w_c of camera 0).
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct StereoFrame {
  int index = 0;
  double stamp_s = 0;
  cv::Mat left, right;  // CV_8UC1, same size
};

class KittiSequence {
 public:
  /// Opens and validates the folder: every file present and well formed, as many left and right
  /// images as lines in times.txt, first left/right pair readable and of one size (which sets
  /// camera().width/height). `poses_path` overrides "<dir>/poses.txt"; when neither exists, no poses.
  /// Throws DataError naming the offending file.
  static KittiSequence open(const std::string& dir, const std::string& poses_path = "");

  const std::string& directory() const { return dir_; }
  const StereoCamera& camera() const { return camera_; }
  size_t size() const { return times_.size(); }
  const std::vector<double>& times() const { return times_; }
  bool hasPoses() const { return !poses_.empty(); }
  /// Ground truth T_w_c of camera 0, one per frame (empty when hasPoses() is false).
  const std::vector<Pose3>& poses() const { return poses_; }
  const std::string& leftPath(size_t i) const { return left_.at(i); }
  const std::string& rightPath(size_t i) const { return right_.at(i); }

  /// Loads frame i as 8-bit grey (colour PNGs are converted). Throws DataError for an unreadable
  /// image, a pixel format other than 8-bit grey/colour, or a size differing from the sequence's.
  StereoFrame load(size_t i) const;

 private:
  std::string dir_;
  StereoCamera camera_;
  std::vector<double> times_;
  std::vector<Pose3> poses_;
  std::vector<std::string> left_, right_;
};

/// Reads one image as 8-bit grey with the same checks as KittiSequence::load.
cv::Mat readGrayImage(const std::string& path);

}  // namespace binloop
