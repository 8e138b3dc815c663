#include "binloop/messages/loop_closure.h"

#include <stdexcept>

namespace binloop::msg {

const char* loopStatusName(LoopStatus s) {
  switch (s) {
    case LoopStatus::kAccepted:
      return "accepted";
    case LoopStatus::kHeld:
      return "held";
    case LoopStatus::kAgreed:
      return "agreed";
    case LoopStatus::kTooFewMatches:
      return "too_few_matches";
    case LoopStatus::kNoConsensus:
      return "no_consensus";
    case LoopStatus::kTooFewInliers:
      return "too_few_inliers";
    case LoopStatus::kBeyondDriftBound:
      return "beyond_drift_bound";
    case LoopStatus::kLargeResidual:
      return "large_residual";
    case LoopStatus::kUnknownKeyframe:
      return "unknown_keyframe";
  }
  return "unknown";
}

LoopStatus parseLoopStatus(const std::string& name) {
  for (int i = 0; i <= static_cast<int>(LoopStatus::kLast); ++i)
    if (name == loopStatusName(static_cast<LoopStatus>(i))) return static_cast<LoopStatus>(i);
  throw std::invalid_argument("unknown loop status '" + name + "'");
}

}  // namespace binloop::msg
