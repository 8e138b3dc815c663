#include "binloop/messages/loop_closure.h"

#include <stdexcept>

namespace binloop::msg {

namespace {
constexpr LoopStatus kAll[] = {LoopStatus::kAccepted,      LoopStatus::kHeld,          LoopStatus::kAgreed,
                               LoopStatus::kTooFewMatches, LoopStatus::kNoConsensus,   LoopStatus::kTooFewInliers,
                               LoopStatus::kBeyondDriftBound, LoopStatus::kLargeResidual, LoopStatus::kUnknownKeyframe};
}  // namespace

const char* loopStatusName(LoopStatus s) {
  switch (s) {
    case LoopStatus::kAccepted: return "accepted";
    case LoopStatus::kHeld: return "held";
    case LoopStatus::kAgreed: return "agreed";
    case LoopStatus::kTooFewMatches: return "too_few_matches";
    case LoopStatus::kNoConsensus: return "no_consensus";
    case LoopStatus::kTooFewInliers: return "too_few_inliers";
    case LoopStatus::kBeyondDriftBound: return "beyond_drift_bound";
    case LoopStatus::kLargeResidual: return "large_residual";
    case LoopStatus::kUnknownKeyframe: return "unknown_keyframe";
  }
  return "unknown";
}

LoopStatus parseLoopStatus(const std::string& name) {
  for (LoopStatus s : kAll)
    if (name == loopStatusName(s)) return s;
  throw std::invalid_argument("unknown loop status '" + name + "'");
}

}  // namespace binloop::msg
