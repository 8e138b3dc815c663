#pragma once
// Stereo keypoints for a rectified pair, as ORB-SLAM2 makes them: each left keypoint takes the right
// keypoint with the closest descriptor on (nearly) its row, at a neighbouring octave and within the
// disparity range; the position is then refined to sub-pixel by SAD block matching at the keypoint's
// octave and a parabola through the best SAD and its two neighbours. A final test drops matches whose SAD
// is far above the frame's median, which removes most wrong descriptor matches on repeated texture.
//
// Departures from ORB-SLAM2 (and one option), measured on a real KITTI frame shifted by a known disparity
// (see stereo_matcher_test.cpp; share of matches within 0.2 px, at 12 / 7.5 / 20.25 / 33.7 px):
// - SAD is taken after removing each window's mean, not its centre pixel: 47/32/36/36 % -> 92/85/81/73 %.
//   A FAST corner's centre pixel differs from its neighbours by construction, so sliding one pixel shifts
//   the offset of the whole window. `centre_pixel_offset` restores ORB-SLAM2's choice.
// - `fit = kEquiangular` fits two lines of opposite slope instead of a parabola: 97/94/95/94 %. SAD grows
//   linearly away from a match, so a parabola's vertex is pulled towards the integer pixel. The parabola
//   stays the default (ORB-SLAM2's and the choice) until SLAM results say otherwise.
// - The outlier test rejects SAD > factor * median. ORB-SLAM2 keeps SAD < factor * median, which drops
//   every match when the median is 0 (noise-free images, e.g. rendered or shifted ones).
#include <vector>

#include "binloop/features/orb_slam_extractor.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct StereoMatchParams {
  int max_hamming = 75;     // best descriptor must be below this: ORB-SLAM2's (TH_HIGH + TH_LOW) / 2
  double min_depth_m = 0;   // nearest depth searched; 0 = one baseline (ORB-SLAM2), i.e. disparity <= fx
  float row_band_px = 2.f;  // a right keypoint is a candidate for rows y ± this times its level scale
  int sad_half_window = 5;  // 11x11 SAD window, at the left keypoint's octave
  int sad_search_px = 5;    // the window slides ± this many level pixels around the descriptor match
  float sad_outlier_factor = 1.5f * 1.4f;  // reject SAD above this times the median SAD of the frame
  double close_depth_baselines = 40;       // isCloseDepth: depth below this many baselines
  bool centre_pixel_offset = false;        // true: SAD windows offset by their centre pixel (ORB-SLAM2)
  // Not the matcher's: whether the estimators (tracking's pose optimisation, local BA) take a far match's
  // disparity as a measurement (true, ORB-SLAM2's way) or only its bearing (measuredRightX,
  // map/keypoint_geometry.h; better scale on real frames, worse recovery after long gaps: docs/decisions.md).
  bool far_disparity = true;
  enum class SubPixelFit { kParabola, kEquiangular };
  SubPixelFit fit = SubPixelFit::kParabola;  // through the best SAD and its two neighbours

  bool operator==(const StereoMatchParams& o) const;
  bool operator!=(const StereoMatchParams& o) const { return !(*this == o); }
};

struct StereoMatches {
  std::vector<float> right_x;  // per left keypoint: x in the right image, level-0 pixels, or -1
  std::vector<float> depth;    // per left keypoint: bf / disparity in metres, or -1
  int matched = 0;             // entries with depth > 0
  int rejected_by_sad = 0;     // refined matches dropped by the outlier test
  float sad_threshold = 0;     // that test's threshold (factor * median), grey levels summed over the window
};

/// Pyramids must have the levels the keypoints' octaves name (OrbSlamExtractor::pyramid of each image)
/// and equal sizes left and right. Throws FeatureError for keypoints and descriptors of different counts, an
/// octave without a pyramid level, differing pyramids, a camera without a positive fx·b, or parameters out
/// of range.
StereoMatches matchStereo(const OrbFeatures& left, const ImagePyramid& left_pyramid, const OrbFeatures& right,
                          const ImagePyramid& right_pyramid, const StereoCamera& cam,
                          const StereoMatchParams& p = {});

/// ORB-SLAM2's "close" point, whose depth is trusted from a single stereo frame: 0 < depth < 40 baselines
/// (by default). Far points are only used for rotation until triangulated over frames.
bool isCloseDepth(float depth_m, const StereoCamera& cam, const StereoMatchParams& p = {});

}  // namespace binloop
