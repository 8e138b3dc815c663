#pragma once
// LoopClosure: loop closing -> the logs, rviz and the user, one per loop it verified (accepted or not).
// Maps 1:1 onto binloop/LoopClosure.
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>

#include "binloop/map/ids.h"
#include "binloop/types/pose.h"

namespace binloop::msg {

/// What loop closing made of a verified candidate.
enum class LoopStatus : uint8_t {
  kAccepted,                 // corrected the map
  kHeld,                     // waiting for a second loop to confirm it
  kAgreed,                   // a held loop that a later one confirmed
  kTooFewMatches,            // rejected by verification (LoopRejection)
  kNoConsensus,              // ...
  kTooFewInliers,            // ...
  kBeyondDriftBound,         // the correction is more than odometry's drift since the match can explain
  kLargeResidual,            // the optimisation could not satisfy the loop edge
  kUnknownKeyframe,          // a keyframe this stage does not hold
  kLast = kUnknownKeyframe,  // a new status goes before this line
};
/// "accepted", "held", "agreed", "too_few_matches", ...: the name logs and ROS messages carry.
const char* loopStatusName(LoopStatus s);
/// The status of a name loopStatusName gives; throws std::invalid_argument for any other.
LoopStatus parseLoopStatus(const std::string& name);
inline std::ostream& operator<<(std::ostream& o, LoopStatus s) { return o << loopStatusName(s); }

struct LoopClosure {
  SlamKeyframeId query = kNoId, match = kNoId;
  uint64_t query_frame = 0, match_frame = 0;
  std::string model;  // which detector proposed it, or "external"
  LoopStatus status = LoopStatus::kAccepted;
  std::string detail;  // the numbers behind the status, one line
  Pose3 T_query_match = Pose3::Identity();
  int matches = 0, inliers = 0;
  double correction_m = 0;    // how far the loop moves the query keyframe
  double drift_bound_m = 0;   // what odometry's drift since the match can explain
  double residual_ratio = 0;  // sqrt(loop edge chi2 after / before the optimisation)
  int keyframes_corrected = 0;
  double verify_ms = 0, optimize_ms = 0;
};

using LoopClosurePtr = std::shared_ptr<const LoopClosure>;

}  // namespace binloop::msg
