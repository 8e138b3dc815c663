#pragma once
// Matches between two keyframes' keypoints that have no map point yet, for triangulation (ORB-SLAM2's
// SearchForTriangulation). Both poses are known, so a keypoint in one keyframe can only match a keypoint
// near its epipolar line in the other: the second keyframe's candidates are binned in cells, a keypoint
// visits the cells its band crosses, and only candidates within the band pay for a Hamming distance.
// ORB-SLAM2 narrows the pairs with vocabulary nodes instead; the line test keeps mapping independent of any
// vocabulary. The result is the same as testing every pair (ties go to the lower index).
#include <utility>
#include <vector>

#include "binloop/map/scale_pyramid.h"
#include "binloop/messages/keyframe.h"
#include "binloop/types/pose.h"

namespace binloop {

/// One keyframe as the matcher sees it; point_ids[i] != kNoId marks keypoints that are not candidates.
struct EpipolarView {
  const Pose3* T_w_c;
  const StereoCamera* camera;
  const std::vector<msg::KeyPoint>* keypoints;
  const Descriptors* descriptors;
  const std::vector<MapPointId>* point_ids;
};

struct EpipolarParams {
  int max_hamming = 50;        // ORB-SLAM2's TH_LOW
  double line_chi2 = 3.84;     // squared distance to the epipolar line over the level variance (1 dof, 95 %)
  float epipole_px = 10;       // mono pairs: a keypoint this close to the epipole (times its level's scale)
                               // says nothing about depth
  bool check_rotation = true;  // keep matches whose angle change is among the commonest
};

/// The fundamental matrix F with x_b^T F x_a = 0 for homogeneous pixel coordinates of one point seen in
/// both keyframes: F = K^-T [t_ba]x R_ba K^-1.
Eigen::Matrix3d fundamentalMatrix(const Pose3& T_w_a, const Pose3& T_w_b, const StereoCamera& cam);

/// Pairs (index in a, index in b) that are each other's best match below max_hamming among the candidates
/// within the epipolar band, after the rotation check.
std::vector<std::pair<int, int>> matchAlongEpipolarLines(const EpipolarView& a, const EpipolarView& b,
                                                         const ScalePyramid& s, const EpipolarParams& p = {});

}  // namespace binloop
