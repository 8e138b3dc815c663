#pragma once
// Trajectory accuracy against ground truth, as every binloop tool and benchmark reports it: the absolute
// trajectory error after a rigid (SE(3), no scale) Umeyama alignment, and the KITTI devkit's relative errors
// over path segments of 100..800 m.
//
// Matching an estimate to the ground truth (docs/tools.md: eval-traj):
// - KITTI files (12 numbers per line) carry no stamps: line i is frame i, so they hold every frame from 0
//   (a prefix is accepted; more lines than the ground truth is an error).
// - TUM files ("stamp tx ty tz qx qy qz qw") may hold any subset of frames, e.g. keyframes only. Their
//   stamps are matched to the ground truth's times.txt within a tolerance (1 ms), or, when the stamps are
//   whole frame indices, by index. Every estimate pose must find its own frame; none may share one.
// All errors in the input throw DataError with a message a user can act on.
#include <string>
#include <vector>

#include "binloop/types/pose.h"

namespace binloop {

enum class TrajectoryFormat { kitti, tum };

/// An estimated trajectory as read from a file; for KITTI files stamp_s is the line's pose index.
struct EstimateFile {
  TrajectoryFormat format = TrajectoryFormat::kitti;
  Trajectory poses;
};

/// Reads a trajectory whose format is told by its first pose line: 12 numbers KITTI, 8 TUM (every line
/// must then have the same count). Throws DataError for an empty file, a NaN or infinite number, a
/// line of another length, and whatever readKittiPoses/readTumTrajectory reject.
EstimateFile readEstimateFile(const std::string& path);

/// readKittiPoses, plus: an empty file and non-finite numbers are errors.
std::vector<Pose3> readGroundTruthPoses(const std::string& path);

const char* formatName(TrajectoryFormat f);  // "KITTI" or "TUM"

/// Estimate poses paired with their ground-truth frames, in increasing frame order.
struct MatchedPoses {
  std::vector<int> frames;     // ground-truth frame index of each pair
  std::vector<Pose3> gt, est;  // T_w_c of camera 0, each in its own world frame
  std::string rule;            // how they were matched, in words ("by frame index (KITTI line = frame)")
  size_t gt_frames = 0;        // poses in the ground truth
};

/// KITTI estimates (stamp = line) and TUM estimates whose stamps are frame indices. A stamp that is not a
/// whole number, lies outside the ground truth, or repeats an earlier frame throws DataError. `source`
/// names the estimate in messages.
MatchedPoses matchByFrameIndex(const std::vector<Pose3>& gt, const EstimateFile& est,
                               const std::string& source = "estimate");

struct TimeMatchOptions {
  double tolerance_s = 1e-3;
  double stamp_offset_s = 0;  // the estimate's stamps are gt_times + this (kitti2bag's bags: + 1 s)
};

/// TUM estimates: each stamp, less the offset, is matched to the nearest of `gt_times` (one per
/// ground-truth pose, non-decreasing, e.g. KITTI's times.txt) and must lie within the tolerance of it.
MatchedPoses matchByTime(const std::vector<Pose3>& gt, const std::vector<double>& gt_times,
                         const EstimateFile& est, const TimeMatchOptions& options = {},
                         const std::string& source = "estimate");

/// T_gt_est minimising sum |gt_i - T * est_i|^2 over rotations and translations (Umeyama 1991 without
/// scale). Needs at least 3 pairs of equal count; throws DataError otherwise.
Pose3 alignUmeyama(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt);

struct RelativeErrorOptions {
  int step_frames = 10;  // a segment starts every this many ground-truth frames (the devkit's step)
  std::vector<double> lengths_m{100, 200, 300, 400, 500, 600, 700, 800};
};

struct RelativeErrors {
  bool valid = false;  // false: no segment fits; `reason` says why, and the errors are NaN
  std::string reason;
  double t_rel_pct;           // mean over all segments of |t_err| / length, in percent
  double r_rel_deg_per_100m;  // mean over all segments of angle(R_err) / length, in degrees per 100 m
  int segments = 0;
  double path_length_m = 0;  // along the matched ground-truth poses
};

/// The KITTI devkit's relative errors. Segments start at the first matched pose at or after ground-truth
/// frames 0, step, 2 step, ... (with every frame matched: every step-th frame, as the devkit does); a
/// segment of length L from pose i ends at the first pose j whose distance travelled along the matched
/// ground truth is >= dist(i) + L. Its error is (gt_i^-1 gt_j)^-1 (est_i^-1 est_j).
RelativeErrors kittiRelativeErrors(const MatchedPoses& m, const RelativeErrorOptions& options = {});

struct TrajectoryMetrics {
  Pose3 T_gt_est = Pose3::Identity();  // aligns the estimate onto the ground truth
  double ate_rmse_m = 0;
  RelativeErrors relative;
};

/// Alignment, ATE and relative errors of matched poses. Throws DataError when fewer than 3 poses are
/// matched or a pose is not finite.
TrajectoryMetrics evaluateTrajectory(const MatchedPoses& m, const RelativeErrorOptions& options = {});

}  // namespace binloop
