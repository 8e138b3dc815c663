#pragma once
// Loop-detection metrics, as `eval-loops` reports them: each query keyframe predicts at most one loop
// (its best candidate, with a confidence); sweeping a threshold over the confidences gives the
// precision-recall curve, its area, and the recall at 100 % precision.
#include <set>
#include <utility>
#include <vector>

namespace binloop {

struct LoopPrediction {
  int query = 0;
  int candidate = -1;  // frame index; -1: no candidate at all
  double confidence = 0;
  bool passed = false;  // the candidate beat the model's own bar (a candidate, not the best rejected)
  /// Predictions of a higher tier rank above every prediction of a lower one, whatever their confidence:
  /// behind the consistency check, chains of candidates (tier 1) come before chains that pass through a
  /// keyframe that failed its bar (tier 0), as ORB-SLAM2 only chains candidates.
  int tier = 0;
};

struct PrPoint {
  double threshold, precision, recall;
  int tier = 0;
};

struct LoopMetrics {
  std::vector<PrPoint> curve;  // one point per distinct confidence, descending
  int positives = 0;           // queries with a ground-truth loop that can be found
  double r_at_100p = 0;
  double threshold_100p = 0;  // lowest confidence at which precision is still 1 (inf when none)
  int tier_100p = 0;          // ... within this tier
  double auc = 0;             // area under the PR curve (precision summed over recall steps)
  double precision_at_bar = 0, recall_at_bar = 0;  // of the predictions that passed the model's own bar
};

/// `truth`: every (query, ref) ground-truth pair; `positive_queries`: queries that have at least one
/// findable ref (ref stored before the query and outside its ignored window). A prediction whose pair is in
/// `ignored` (and not in `truth`) counts neither right nor wrong, as if the query had proposed nothing: a
/// near miss just beyond the ground truth's radius should not set the bar for a whole route.
LoopMetrics evaluateLoops(const std::vector<LoopPrediction>& predictions,
                          const std::set<std::pair<int, int>>& truth, const std::set<int>& positive_queries,
                          const std::set<std::pair<int, int>>& ignored = {});

/// Of `queries`, how many have a correct prediction at or above (tier, threshold).
int foundAt(const std::vector<LoopPrediction>& predictions, const std::set<std::pair<int, int>>& truth,
            const std::set<int>& queries, double threshold, int tier = 0);

}  // namespace binloop
