#pragma once
// loops.csv: the runner's log of loop detection and closing, one row per keyframe and model queried (the
// active model's row also carries what loop closing made of its proposal), plus a row per held loop that
// expired. eval-slam reads the accepted loops back from it.
#include <string>
#include <vector>

#include "binloop/pipeline/slam_pipeline.h"

namespace binloop {

/// `ground_truth` (T_w_c by frame index), when given, adds each verified loop's error against it
/// (gt_error_m, gt_error_deg; eval/slam_evaluation.h's loopPoseError).
void writeLoopLog(const std::string& path, const std::vector<SlamPipeline::LoopLogEntry>& log,
                  const std::vector<Pose3>* ground_truth = nullptr);

struct LoggedLoop {
  std::string model;
  msg::LoopStatus status = msg::LoopStatus::kAccepted;
  uint64_t query_frame = 0, match_frame = 0;
  int inliers = 0;
  double correction_m = 0;
  bool has_pose = false;  // false in a loops.csv written before the relative pose was logged
  Pose3 T_query_match = Pose3::Identity();
};
/// Every row of loops.csv that names a verified loop (accepted, held, or rejected by closing).
/// Throws DataError for a missing file or a malformed row.
std::vector<LoggedLoop> readLoopLog(const std::string& path);

}  // namespace binloop
