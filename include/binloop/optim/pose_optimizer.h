#pragma once
// Pose-only optimisation of one stereo frame against fixed map points, as ORB-SLAM2's
// Optimizer::PoseOptimization: a few rounds of Levenberg-Marquardt; after each round every observation
// (including those left out) is classified at the new pose, and outliers sit out the next round. The
// residuals and the pose parametrisation are in reprojection_costs.h. Ceres runs on one thread, so the same
// input gives bit-identical output.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

/// A map point seen in the frame.
struct PoseObservation {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // the point, world frame (held fixed)
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();   // its keypoint in the left image (px)
  double u_right = -1;    // its u in the right image (px); negative: monocular (no depth)
  double inv_sigma2 = 1;  // 1 / scale_factor^(2 octave) of the keypoint
};

struct PoseOptimizerParams {
  int rounds = 4;                 // of optimisation + classification
  int iterations_per_round = 10;  // Levenberg-Marquardt iterations (fewer if Ceres converges)
  int robust_rounds = 3;          // the first rounds use the Huber loss, the rest plain squares
  // An observation is an outlier when chi2 exceeds these (chi-square 95 %, 2 and 3 dof) or its point is
  // behind the camera.
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;
  double huber_delta_mono = std::sqrt(5.991);
  double huber_delta_stereo = std::sqrt(7.815);
  /// When more observations than this are active, each round solves on an even spread of this many of them
  /// (every k-th) and still classifies all of them at the new pose. Six unknowns are fixed long before a
  /// thousand points; the solve's cost is linear in the count. Zero: solve on all of them.
  int max_solve_observations = 0;
};

struct PoseOptimizationResult {
  Pose3 T_c_w = Pose3::Identity();  // the refined pose
  /// Per observation: at the refined pose, chi2 is above its threshold or the point is behind the camera.
  std::vector<bool> outlier;
  int num_inliers = 0;
  /// 1/2 sum of chi2 over the final inliers, at the initial pose and at the refined one (same observations,
  /// no robust loss, so the two compare).
  double initial_cost = 0, final_cost = 0;
  int rounds_run = 0;  // rounds that ran a solve (a round needs 3 inliers, the fewest that fix a pose)
  int iterations = 0;  // Levenberg-Marquardt iterations over all rounds
};

/// Refines T_c_w (world -> left camera) from the observations. Throws std::invalid_argument on invalid input:
/// non-finite values, inv_sigma2 <= 0, fx or fy <= 0, a stereo observation with no baseline, a pose whose
/// rotation is not orthonormal, or invalid parameters. With fewer than 3 inliers at the start the pose is
/// returned as given, with its classification.
PoseOptimizationResult optimizePose(const StereoCamera& camera, const Pose3& T_c_w,
                                    const std::vector<PoseObservation>& observations,
                                    const PoseOptimizerParams& params = {});

}  // namespace binloop
