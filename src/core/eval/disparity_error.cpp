#include "binloop/eval/disparity_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "binloop/util/median.h"

namespace binloop {

std::vector<DisparityError> disparityErrors(const std::vector<msg::KeyPoint>& keypoints, const cv::Mat& depth,
                                            const StereoCamera& cam) {
  if (depth.type() != CV_32F || depth.cols != cam.width || depth.rows != cam.height)
    throw std::invalid_argument("disparityErrors: the true depth must be CV_32F of the camera's size");
  constexpr int kEdge = 2;  // pixels beyond the bilinear sample's 2x2 cell that must be as deep
  const double bf = cam.bf();
  std::vector<DisparityError> out;
  for (const msg::KeyPoint& k : keypoints) {
    if (k.depth <= 0) continue;
    const int u = static_cast<int>(k.x), v = static_cast<int>(k.y);
    if (u < kEdge || v < kEdge || u + 1 + kEdge >= depth.cols || v + 1 + kEdge >= depth.rows) continue;
    float lo = depth.at<float>(v, u), hi = lo;
    for (int dv = -kEdge; dv <= kEdge + 1; ++dv) {
      for (int du = -kEdge; du <= kEdge + 1; ++du) {
        lo = std::min(lo, depth.at<float>(v + dv, u + du));
        hi = std::max(hi, depth.at<float>(v + dv, u + du));
      }
    }
    if (!std::isfinite(hi) || lo <= 0 || hi > 1.03f * lo) continue;
    // The truth at the keypoint's sub-pixel position, bilinear between the four pixels around it.
    const float ax = k.x - u, ay = k.y - v;
    const double z = (1 - ax) * (1 - ay) * depth.at<float>(v, u) + ax * (1 - ay) * depth.at<float>(v, u + 1) +
                     (1 - ax) * ay * depth.at<float>(v + 1, u) + ax * ay * depth.at<float>(v + 1, u + 1);
    DisparityError e;
    e.true_disparity = static_cast<float>(bf / z);
    e.error = static_cast<float>(bf / k.depth - bf / z);
    out.push_back(e);
  }
  return out;
}

std::vector<DisparityErrorSummary> summariseDisparityErrors(const std::vector<DisparityError>& errors,
                                                            const std::vector<double>& edges) {
  std::vector<DisparityErrorSummary> out;
  for (size_t b = 0; b + 1 < edges.size(); ++b) {
    DisparityErrorSummary s;
    s.lo = edges[b];
    s.hi = edges[b + 1];
    std::vector<double> e;
    size_t wrong = 0;
    for (const DisparityError& d : errors) {
      if (d.true_disparity < s.lo || d.true_disparity >= s.hi) continue;
      e.push_back(d.error);
      if (std::abs(d.error) > 1) ++wrong;
    }
    s.n = e.size();
    if (!e.empty()) {
      s.median = median(e);
      std::vector<double> dev;
      dev.reserve(e.size());
      for (double x : e) dev.push_back(std::abs(x - s.median));
      s.mad = median(std::move(dev));
      s.wrong = static_cast<double>(wrong) / e.size();
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace binloop
