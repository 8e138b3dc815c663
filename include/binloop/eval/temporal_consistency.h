#pragma once
// ORB-SLAM2's consistency check (of the loop-detection stage) in a form a threshold can sweep: a loop is
// reported for a query only when it and the queries just before it each have a candidate, and every
// candidate's group (itself and its neighbours) overlaps the previous one's. For a threshold t the check
// passes exactly when such a chain exists among candidates of confidence >= t, so a chain's confidence is
// its weakest link, and the precision-recall sweep works on that.
#include <utility>
#include <vector>

#include "binloop/eval/loop_metrics.h"

namespace binloop {

/// One keyframe a query offered: a candidate (passed the model's bar) or its best rejected keyframe.
struct Offer {
  int frame = 0;
  double confidence = 0;
  bool passed = false;
};

/// Everything one query offered.
struct QueryOffers {
  int query = 0;
  std::vector<Offer> offers;
};

/// `queries` are consecutive keyframes in order. A chain has `chain` links (ORB-SLAM2: 3); two candidates
/// are consistent when their frames are at most `max_gap` apart (groups of ±2 keyframes overlap when the
/// candidates are 4 keyframes apart). Returns one prediction per query: the end of its strongest chain, with
/// the chain's weakest confidence, or no candidate when no chain reaches that long. When a chain exists
/// among offers that all passed their bar, the strongest such chain is the prediction instead, with
/// `passed` set and tier 1 (it ranks above every chain through a rejected keyframe).
std::vector<LoopPrediction> consistentPredictions(const std::vector<QueryOffers>& queries, int chain,
                                                  int max_gap);

}  // namespace binloop
