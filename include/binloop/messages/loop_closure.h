#pragma once
// LoopClosure: loop closing -> the logs, rviz and the user, one per loop it verified (accepted or not).
// Maps 1:1 onto binloop/LoopClosure.
#include <memory>
#include <string>

#include "binloop/map/ids.h"
#include "binloop/types/pose.h"

namespace binloop::msg {

struct LoopClosure {
  SlamKeyframeId query = kNoId, match = kNoId;
  uint64_t query_frame = 0, match_frame = 0;
  std::string model;   // which detector proposed it, or "external"
  // accepted, held (waiting for a second loop), agreed (with a held loop that a later one confirmed), or
  // the reason it was rejected: too_few_matches, no_consensus, too_few_inliers, beyond_drift_bound,
  // large_residual, unknown_keyframe
  std::string status;
  std::string detail;  // the numbers behind the status, one line
  Pose3 T_query_match = Pose3::Identity();
  int matches = 0, inliers = 0;
  double correction_m = 0;  // how far the loop moves the query keyframe
  double drift_bound_m = 0; // what odometry's drift since the match can explain
  double residual_ratio = 0;  // sqrt(loop edge chi2 after / before the optimisation)
  int keyframes_corrected = 0;
  double verify_ms = 0, optimize_ms = 0;
};

using LoopClosurePtr = std::shared_ptr<const LoopClosure>;

}  // namespace binloop::msg
