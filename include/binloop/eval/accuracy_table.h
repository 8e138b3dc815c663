#pragma once
// Several runs of one system on one sequence, summed up as the accuracy benchmark reports them (median and
// range of ATE and t_rel, loops that were wrong in any run, revisits closed in every run), and a peer's run
// folders (ORB-SLAM2's CameraTrajectory.txt, loops.txt, TrackingTimes.txt) scored by the same rules.
// A multi-threaded SLAM differs from run to run, so one run says little: compare medians and spreads.
#include <string>
#include <vector>

#include "binloop/eval/slam_evaluation.h"
#include "binloop/eval/trajectory_metrics.h"

namespace binloop {

/// One run, scored.
struct RunScore {
  TrajectoryMetrics metrics;
  LoopScore loops;
  int lost_frames = 0;
};

/// Runs of one system (a model, or a peer's configuration) summed up.
struct AccuracyRow {
  std::string name;
  int runs = 0;
  double ate_median = 0, ate_min = 0, ate_max = 0;
  double t_rel_median = 0, t_rel_min = 0, t_rel_max = 0;  // NaN when the path is too short for segments
  double r_rel_median = 0;
  double loops_median = 0;      // accepted loops per run
  int loops_wrong = 0;          // over all runs: accepted loops too far apart or with a wrong relative pose
  int wrong_unjudged_pose = 0;  // runs whose loops had no relative pose to judge (a peer's loops.txt)
  int segments = 0;             // revisit segments in the ground truth
  int segments_every_run = 0;   // segments closed in every run
  int lost_max = 0;             // frames not tracked, the worst run
  double spread() const { return ate_min > 0 ? ate_max / ate_min : 0; }
};

/// Throws DataError for no runs.
AccuracyRow summarizeRuns(const std::string& name, const std::vector<RunScore>& runs, int segments);

/// A peer's runs in `dir`: every sub-folder holding CameraTrajectory.txt (KITTI, a line per frame),
/// optionally loops.txt ("query_frame matched_frame" per line) and TrackingTimes.txt ("frame stamp
/// seconds state", state 2 = tracked). Runs are grouped by folder name without its "-N" suffix ("loops-1",
/// "loops-2" -> "loops"), each group one row named `prefix` + group. Throws DataError for a folder with no
/// run or a malformed file.
std::vector<AccuracyRow> scorePeerRuns(const std::string& dir, const std::string& prefix,
                                       const std::vector<Pose3>& gt,
                                       const std::vector<RevisitSegment>& segments);

/// The rows as an aligned text table (`csv` false) or CSV, header first.
std::string formatAccuracyTable(const std::vector<AccuracyRow>& rows, bool csv);

}  // namespace binloop
