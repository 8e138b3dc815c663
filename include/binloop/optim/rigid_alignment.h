#pragma once
// The rigid transform between two sets of corresponding 3-D points, for loop verification: a loop between
// two stereo keyframes is a rotation and a translation between their point clouds (stereo fixes the scale,
// so ORB-SLAM2's Sim3 becomes SE3 here). Horn's closed form (1987) gives it from three or more pairs;
// RANSAC over minimal samples of three finds it among wrong matches.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

/// T_a_b minimising sum |a_i - T_a_b b_i|^2 (Horn 1987, unit quaternions): with centroids removed,
/// M = sum b_i a_i^T; the rotation is the eigenvector of the largest eigenvalue of the symmetric 4x4
///   N = [ tr M        (M23 - M32)  (M31 - M13)  (M12 - M21) ]
///       [ .           M11-M22-M33  (M12 + M21)  (M31 + M13) ]
///       [ .           .            -M11+M22-M33 (M23 + M32) ]
///       [ .           .            .            -M11-M22+M33 ]
/// read as a quaternion (w, x, y, z), and t = mean(a) - R mean(b). Empty for fewer than 3 pairs or
/// collinear points (the rotation about their line is not determined).
std::optional<Pose3> hornAlignment(const std::vector<Eigen::Vector3d>& a,
                                   const std::vector<Eigen::Vector3d>& b);

struct RigidRansacParams {
  int iterations = 300;  // at most
  /// Stop once a sample of three inliers has been drawn with this probability, at the inlier share of the
  /// best model so far: log(1 - confidence) / log(1 - w^3) iterations (w = 0.5: 52; w = 0.3: 253). Zero
  /// runs all `iterations`.
  double confidence = 0.999;
  /// A pair is an inlier when |a - T b| is below this many metres plus `relative` times the distance of
  /// a from its camera (stereo depth error grows with distance).
  double absolute_m = 0.1;
  double relative = 0.02;
  int min_inliers = 20;
};

struct RigidRansacResult {
  bool ok = false;
  Pose3 T_a_b = Pose3::Identity();  // refit by Horn on every inlier
  std::vector<uint8_t> inlier;
  int inliers = 0;
  int iterations = 0;  // samples drawn
};

/// `a` in a frame whose origin is a's camera (its distances set the thresholds). Deterministic for a seed.
RigidRansacResult rigidRansac(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                              const RigidRansacParams& p, uint64_t seed);

}  // namespace binloop
