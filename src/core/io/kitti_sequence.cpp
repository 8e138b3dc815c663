#include "binloop/io/kitti_sequence.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/io/data_error.h"
#include "binloop/io/filesystem.h"
#include "binloop/io/kitti_calib.h"
#include "binloop/io/trajectory_io.h"

namespace fs = std::filesystem;

namespace binloop {

cv::Mat readGrayImage(const std::string& path) {
  requireFile(path);
  cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw dataError(path, 0, "cannot be decoded as an image (corrupt or not an image)");
  if (img.depth() != CV_8U)
    throw dataError(path, 0, "has " + std::to_string(8 * img.elemSize1()) + "-bit pixels; expected 8-bit");
  if (img.channels() == 1) return img;
  cv::Mat gray;
  if (img.channels() == 3) {
    cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
  } else if (img.channels() == 4) {
    cv::cvtColor(img, gray, cv::COLOR_BGRA2GRAY);
  } else {
    throw dataError(path, 0, "has " + std::to_string(img.channels()) + " channels; expected 1, 3 or 4");
  }
  return gray;
}

KittiSequence KittiSequence::open(const std::string& dir, const std::string& poses_path) {
  requireDirectory(dir);
  KittiSequence s;
  s.dir_ = dir;
  const fs::path root(dir);
  s.camera_ = readKittiCalib((root / "calib.txt").string());
  s.times_ = readTimes((root / "times.txt").string());
  s.left_ = listFilesNatural((root / "image_0").string(), {".png"});
  s.right_ = listFilesNatural((root / "image_1").string(), {".png"});
  const auto count_error = [&](const std::string& sub, size_t n) {
    return dataError((root / sub).string(), 0,
                     "holds " + std::to_string(n) + " PNG images but times.txt has " +
                         std::to_string(s.times_.size()) + " lines");
  };
  if (s.times_.empty()) throw dataError((root / "times.txt").string(), 0, "is empty");
  if (s.left_.size() != s.times_.size()) throw count_error("image_0", s.left_.size());
  if (s.right_.size() != s.times_.size()) throw count_error("image_1", s.right_.size());
  for (size_t i = 0; i < s.left_.size(); ++i) {
    if (fs::path(s.left_[i]).filename() != fs::path(s.right_[i]).filename()) {
      throw dataError(s.right_[i], 0,
                      "is paired with " + s.left_[i] + ": left and right file names must match");
    }
  }

  const cv::Mat first = readGrayImage(s.left_[0]);
  s.camera_.width = first.cols;
  s.camera_.height = first.rows;
  s.load(0);  // checks the right image of the first pair too

  std::string pp = poses_path.empty() ? (root / "poses.txt").string() : poses_path;
  if (!poses_path.empty() || fs::exists(pp)) {
    s.poses_ = readKittiPoses(pp);
    if (s.poses_.size() != s.times_.size()) {
      throw dataError(pp, 0,
                      "has " + std::to_string(s.poses_.size()) + " poses but the sequence has " +
                          std::to_string(s.times_.size()) + " frames");
    }
  }
  return s;
}

StereoFrame KittiSequence::load(size_t i) const {
  if (i >= size()) {
    throw DataError("frame " + std::to_string(i) + " is past the sequence end (" + std::to_string(size()) +
                    " frames) in " + dir_);
  }
  StereoFrame f;
  f.index = static_cast<int>(i);
  f.stamp_s = times_[i];
  f.left = readGrayImage(left_[i]);
  f.right = readGrayImage(right_[i]);
  const auto size_str = [](const cv::Mat& m) {
    return std::to_string(m.cols) + "x" + std::to_string(m.rows);
  };
  if (f.left.size() != f.right.size())
    throw dataError(right_[i], 0, "is " + size_str(f.right) + " but its left image is " + size_str(f.left));
  if (f.left.cols != camera_.width || f.left.rows != camera_.height) {
    throw dataError(left_[i], 0,
                    "is " + size_str(f.left) + " but the sequence's first image is " +
                        std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  }
  return f;
}

}  // namespace binloop
