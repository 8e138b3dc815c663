#pragma once
// Local bundle adjustment on plain data, as ORB-SLAM2's Optimizer::LocalBundleAdjustment: the local
// keyframes and the points they see move, the other keyframes that see those points hold still
// (`fixed`). Two stages: a few iterations with the Huber loss over every observation; then the
// observations whose chi2 is over the threshold, or whose point is behind the camera, are left out and
// the rest refined with plain squares. Residuals and pose parametrisation: reprojection_costs.h.
//
// Levenberg-Marquardt with the points eliminated by the Schur complement, our own (src/core/optim/
// schur_lm.h) rather than Ceres's: every block has a size known at compile time and the Jacobians are in
// closed form, which made a KITTI window's adjustment 4.7 times faster (docs/decisions.md). It runs on one
// thread, so the same input gives bit-identical output. An optional abort flag (ORB-SLAM2's mbAbortBA:
// set when a new keyframe arrives) stops the solve at the next iteration and keeps what it has so far.
#include <Eigen/Core>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "binloop/types/pose.h"
#include "binloop/types/stereo_camera.h"

namespace binloop {

struct BaKeyframe {
  uint64_t id = 0;
  Pose3 T_c_w = Pose3::Identity();  // world -> left camera
  bool fixed = false;               // held still (ORB-SLAM2's fixed keyframes, and the first keyframe)
};

struct BaPoint {
  uint64_t id = 0;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
};

struct BaObservation {
  std::size_t keyframe = 0;                      // index into BaProblem::keyframes
  std::size_t point = 0;                         // index into BaProblem::points
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // keypoint in the left image (px)
  double u_right = -1;                           // u in the right image (px); negative: monocular
  double inv_sigma2 = 1;                         // 1 / scale_factor^(2 octave) of the keypoint
};

struct BaProblem {
  std::vector<BaKeyframe> keyframes;  // ids unique
  std::vector<BaPoint> points;        // ids unique
  std::vector<BaObservation> observations;
};

/// How the reduced camera system (the keyframes' 6x6 blocks, points eliminated) is factorised. A local
/// window has 10-20 free keyframes, a 60-120 wide system: dense Cholesky. Global BA frees hundreds of
/// keyframes of which each sees only its neighbours' points: sparse Cholesky (CHOLMOD's supernodal LLT).
enum class BaLinearSolver {
  kDenseSchur,   // dense Cholesky of the reduced system (the default)
  kSparseSchur,  // sparse Cholesky of the reduced system
};

struct LocalBaParams {
  int robust_iterations = 5;   // stage 1: Huber loss, every observation
  int refine_iterations = 10;  // stage 2: plain squares, inliers only (0 skips it)
  // An observation is an outlier when chi2 exceeds these (chi-square 95 %, 2 and 3 dof) or its point is
  // behind the camera.
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;
  double huber_delta_mono = std::sqrt(5.991);
  double huber_delta_stereo = std::sqrt(7.815);
  BaLinearSolver linear_solver = BaLinearSolver::kDenseSchur;
};

struct BaRefinedKeyframe {
  std::size_t index = 0;  // into BaProblem::keyframes
  uint64_t id = 0;
  Pose3 T_c_w = Pose3::Identity();
};

/// What a bundle adjustment did, apart from the poses and points it found: what reports and stats keep.
struct BaSummary {
  int num_outliers = 0;  // observations judged outliers at the result
  /// 1/2 sum of chi2 over the final inliers, at the input and at the result (same observations, no
  /// robust loss, so the two compare).
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;         // Levenberg-Marquardt iterations, both stages
  int robust_iterations = 0;  // ... of which stage 1 (Huber) took
  double time_s = 0;          // wall time of the whole call

  double ms() const { return 1000 * time_s; }
};

struct LocalBaResult {
  /// The keyframes that are not fixed, in input order (one with no observation comes back as given).
  std::vector<BaRefinedKeyframe> keyframes;
  /// Every point, in input order (one with no usable observation comes back as given).
  std::vector<BaPoint> points;
  /// Per observation: at the result, chi2 is above its threshold or the point is behind the camera.
  std::vector<bool> outlier;
  BaSummary summary;
  bool aborted = false;  // the abort flag stopped it (stage 2 then does not run)
};

/// Holds the oldest keyframe (lowest id) of every group of keyframes that shares points, directly or
/// through others, and holds none: without it such a group has no gauge and drifts as the damping lets it.
/// That happens to a map segment tracking started afresh after it was lost (Tracker, `restart_after_lost`)
/// until a loop joins it to the rest. Returns how many keyframes it held.
int holdEachUnanchoredGroup(BaProblem& problem);

/// Refines the non-fixed keyframes and the points. `abort`, when given, is read at every iteration; once it
/// is true the solve stops there. Throws std::invalid_argument on invalid input: an index out of range,
/// duplicate ids, non-finite values, inv_sigma2 <= 0, fx or fy <= 0, a stereo observation with no baseline,
/// a pose whose rotation is not orthonormal, or invalid parameters. With no fixed keyframe the gauge
/// (7 dof for mono, 6 for stereo) is free and held only by the damping, as in any BA.
LocalBaResult localBundleAdjustment(const StereoCamera& camera, const BaProblem& problem,
                                    const LocalBaParams& params = {}, std::atomic<bool>* abort = nullptr);

}  // namespace binloop
