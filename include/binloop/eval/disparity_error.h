#pragma once
// How far stereo matching's disparities lie from the truth, on rendered frames whose true depth is known: the
// noise and the bias of the sub-pixel fit (`stereo.equiangular_fit`), which set how far a stereo point's
// depth can be trusted. Used by `eval-stereo` and the stereo matcher's tests.
#include <vector>

#include <opencv2/core.hpp>

#include "binloop/messages/keyframe.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct DisparityError {
  float true_disparity = 0;  // px, fx * baseline / the true depth at the keypoint
  float error = 0;           // measured - true disparity, px
};

/// One sample per stereo-matched keypoint (depth > 0) whose true depth is smooth around it: within 3 % over
/// the 6x6 pixels about it, so that keypoints on an occluding edge, where the true disparity is not one
/// number, are left out. Only the keypoint's surroundings are checked: a keypoint of a coarse pyramid level
/// whose matching window reaches an edge further off is kept, as the matcher meets it. `depth`: the left
/// image's true depth (CV_32F metres, +inf for sky, the camera's size). Throws std::invalid_argument for a
/// depth image of another type or size.
std::vector<DisparityError> disparityErrors(const std::vector<msg::KeyPoint>& keypoints, const cv::Mat& depth,
                                            const StereoCamera& cam);

struct DisparityErrorSummary {
  double lo = 0, hi = 0;  // true disparity range [lo, hi), px
  size_t n = 0;
  double median = 0;  // px: the bias
  double mad = 0;     // median absolute deviation from the median, px: the noise
  double wrong = 0;   // share of samples more than 1 px off (a wrong match, not a sub-pixel error)
};

/// One summary per range between consecutive `edges` (ascending), the ranges without a sample included.
std::vector<DisparityErrorSummary> summariseDisparityErrors(const std::vector<DisparityError>& errors,
                                                            const std::vector<double>& edges);

}  // namespace binloop
