#pragma once
// One stereo pair after feature extraction and stereo matching: what tracking works on. The map point
// matched to each keypoint is filled in by tracking.
#include <cstdint>
#include <string>
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/features/stereo_matcher.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/map/keypoint_grid.h"
#include "binloop/map/scale_pyramid.h"
#include "binloop/messages/keyframe.h"

namespace binloop {

struct Frame {
  uint64_t index = 0;
  double stamp_s = 0;
  std::vector<msg::KeyPoint> keypoints;
  Descriptors descriptors;
  KeypointGrid grid;
  std::vector<MapPointId> points;  // per keypoint, kNoId where unmatched
  std::vector<uint8_t> outlier;    // per keypoint: its match was rejected by the last pose optimisation
  Pose3 T_w_c = Pose3::Identity();
  int stereo_matches = 0;
  double extract_ms = 0, stereo_ms = 0;

  size_t size() const { return keypoints.size(); }
  int matchedInliers() const;
  /// Every keypoint unmatched and no outlier: the state a pose search from scratch starts in.
  void clearMatches();
};

/// Extraction (left and right on two threads) and stereo matching with one set of parameters.
class FrameBuilder {
 public:
  /// Throws std::invalid_argument for a camera without positive focal length, baseline and size.
  FrameBuilder(const StereoCamera& cam, const OrbSlamParams& orb, const StereoMatchParams& stereo);
  /// Throws DataError for an empty image, left/right of different sizes or a size other than the
  /// camera's, or an image that is not 8-bit grey.
  Frame build(const StereoFrame& in) const;
  const ScalePyramid& scales() const { return scales_; }
  const StereoCamera& camera() const { return cam_; }
  const OrbSlamParams& orbParams() const { return extractor_.params(); }

 private:
  StereoCamera cam_;
  OrbSlamExtractor extractor_;
  StereoMatchParams stereo_;
  ScalePyramid scales_;
};

}  // namespace binloop
