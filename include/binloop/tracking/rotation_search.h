#pragma once
// The camera's rotation after frames were lost, found before its position. Over a gap the motion model
// drifts in rotation faster than in position (a car leaving a bend keeps "turning" in the prediction:
// 4-5 degrees, 50-60 px, after 20 missing frames on rendered 06), which puts every point beyond a
// projection search's window. Far points are the cure: their bearing hardly depends on where exactly the
// camera is, so a rotation that lines up many far map points with keypoints of the same look is the
// camera's rotation, and the ordinary search then works around it.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "binloop/messages/map_state.h"
#include "binloop/tracking/frame.h"

namespace binloop {

struct RotationSearchParams {
  double max_angle_deg = 8;    // how far the prediction's rotation may be off (sets the search window)
  double min_distance_m = 25;  // map points at least this far from the predicted camera take part
  int level_slack = 2;         // pyramid levels either side of the predicted one a keypoint may lie on
  int max_hamming = 50;        // ORB-SLAM2's TH_LOW: a candidate must look like the point
  double inlier_px = 4;        // a bearing agrees with the rotation within this many pixels (level 0)
  int iterations = 400;        // RANSAC samples of two pairs
  int min_inliers = 12;
};

struct RotationSearchResult {
  bool ok = false;
  /// The correction: the camera's rotation is predicted.linear() * R_pred_c, its position the prediction's.
  Eigen::Matrix3d R_pred_c = Eigen::Matrix3d::Identity();
  int candidates = 0;  // far points with a candidate keypoint
  int inliers = 0;
};

/// The rotation only two bearings need: R minimising sum |obs_i - R pred_i|^2 over unit vectors (Kabsch,
/// without centroids because every bearing starts at the camera). Identity for fewer than two pairs.
Eigen::Matrix3d rotationBetweenBearings(const std::vector<Eigen::Vector3d>& obs,
                                        const std::vector<Eigen::Vector3d>& pred);

/// Each far point's best-looking keypoint within the window, then RANSAC over pairs for the rotation that
/// most of them agree on, refit on its inliers. Deterministic for a seed.
RotationSearchResult searchRotation(const Frame& f, const Pose3& predicted_T_w_c,
                                    const std::vector<const msg::MapPoint*>& points, const StereoCamera& cam,
                                    const ScalePyramid& s, const RotationSearchParams& p, uint64_t seed);

}  // namespace binloop
