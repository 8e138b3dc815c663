#pragma once
// ORB keypoints and descriptors of one grey image. OpenCV's ORB stands in until binloop has its own
// ORB-SLAM2-style extractor (the SLAM issue); every tool and evaluation gets its features from here, so
// swapping the extractor is one change.
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "binloop/place/binary_descriptor.h"

namespace binloop {

struct OrbParams {
  int features = 1000;
  float scale_factor = 1.2f;
  int levels = 8;
  int fast_threshold = 20;
  /// Spread the features over a grid of cells this wide (pixels of the image given); 0 keeps OpenCV's
  /// strongest-first choice. ORB-SLAM2 spreads its features the same way, for the same reason: place
  /// recognition and tracking both need features from the whole image, not from its busiest texture.
  int grid_cell_px = 64;
  int candidates_factor = 4;  // with a grid: detect this many times `features`, then spread
};

struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  Descriptors descriptors;
};

/// Throws PlaceError for an empty or non-8-bit single-channel image.
OrbFeatures extractOrb(const cv::Mat& gray, const OrbParams& p = {});

}  // namespace binloop
