#include "binloop/tracking/frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <stdexcept>

#include "binloop/io/data_error.h"
#include "binloop/util/stopwatch.h"

namespace binloop {

namespace {
std::string sizeText(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }
}  // namespace

int Frame::matchedInliers() const {
  int n = 0;
  for (size_t i = 0; i < points.size(); ++i) n += points[i] != kNoId && !outlier[i];
  return n;
}

void Frame::clearMatches() {
  std::fill(points.begin(), points.end(), kNoId);
  std::fill(outlier.begin(), outlier.end(), 0);
}

FrameBuilder::FrameBuilder(const StereoCamera& cam, const OrbSlamParams& orb, const StereoMatchParams& stereo)
    : cam_(cam), extractor_(orb), stereo_(stereo), scales_(orb.scale_factor, orb.levels) {
  if (!(cam.fx > 0) || !(cam.fy > 0) || !(cam.baseline_m > 0) || !std::isfinite(cam.cx) ||
      !std::isfinite(cam.cy) || cam.width <= 0 || cam.height <= 0) {
    throw std::invalid_argument("camera: fx, fy and baseline must be positive numbers and the size known (" +
                                cam.describe() + ")");
  }
}

Frame FrameBuilder::build(const StereoFrame& in) const {
  if (in.left.empty() || in.right.empty()) {
    throw DataError("frame " + std::to_string(in.index) + ": empty " + (in.left.empty() ? "left" : "right") +
                    " image");
  }
  if (in.left.size() != in.right.size()) {
    throw DataError("frame " + std::to_string(in.index) + ": left image is " + sizeText(in.left) +
                    " but right is " + sizeText(in.right));
  }
  if (in.left.cols != cam_.width || in.left.rows != cam_.height) {
    throw DataError("frame " + std::to_string(in.index) + ": image is " + sizeText(in.left) +
                    ", calibration says " + std::to_string(cam_.width) + "x" + std::to_string(cam_.height));
  }
  if (in.left.type() != CV_8UC1 || in.right.type() != CV_8UC1)
    throw DataError("frame " + std::to_string(in.index) + ": images must be 8-bit grey (mono8)");

  Frame f;
  f.index = static_cast<uint64_t>(in.index);
  f.stamp_s = in.stamp_s;
  auto t0 = std::chrono::steady_clock::now();
  // The right image on a second thread, as ORB-SLAM2 does: extraction is half of a frame's time.
  auto right_job = std::async(std::launch::async, [&] {
    ImagePyramid p = extractor_.pyramid(in.right);
    OrbFeatures feats = extractor_.extract(p);
    return std::make_pair(std::move(p), std::move(feats));
  });
  ImagePyramid left_pyr = extractor_.pyramid(in.left);
  OrbFeatures left = extractor_.extract(left_pyr);
  auto [right_pyr, right] = right_job.get();
  f.extract_ms = msSince(t0);

  t0 = std::chrono::steady_clock::now();
  StereoMatches sm = matchStereo(left, left_pyr, right, right_pyr, cam_, stereo_);
  f.stereo_ms = msSince(t0);
  f.stereo_matches = sm.matched;

  const size_t n = left.keypoints.size();
  f.keypoints.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& k = left.keypoints[i];
    f.keypoints[i] =
        msg::KeyPoint{k.pt.x, k.pt.y, k.angle, static_cast<uint8_t>(k.octave), sm.right_x[i], sm.depth[i]};
  }
  f.descriptors = std::move(left.descriptors);
  f.grid = KeypointGrid(f.keypoints, cam_.width, cam_.height);
  f.points.assign(n, kNoId);
  f.outlier.assign(n, 0);
  return f;
}

}  // namespace binloop
