#include "binloop/eval/loop_metrics.h"

#include <algorithm>
#include <limits>

namespace binloop {

LoopMetrics evaluateLoops(const std::vector<LoopPrediction>& predictions,
                          const std::set<std::pair<int, int>>& truth, const std::set<int>& positive_queries,
                          const std::set<std::pair<int, int>>& ignored) {
  LoopMetrics m;
  m.positives = static_cast<int>(positive_queries.size());
  m.threshold_100p = std::numeric_limits<double>::infinity();
  std::vector<const LoopPrediction*> p;
  for (const auto& x : predictions) {
    const std::pair<int, int> pair{x.query, x.candidate};
    if (x.candidate >= 0 && (truth.count(pair) || !ignored.count(pair))) p.push_back(&x);
  }
  std::sort(p.begin(), p.end(), [](auto* a, auto* b) {
    return a->tier != b->tier ? a->tier > b->tier : a->confidence > b->confidence;
  });
  int tp = 0, fp = 0, tp_bar = 0, fp_bar = 0;
  double prev_recall = 0;
  for (size_t i = 0; i < p.size();) {
    // Predictions with equal confidence enter together: a threshold cannot separate them.
    size_t j = i;
    for (; j < p.size() && p[j]->tier == p[i]->tier && p[j]->confidence == p[i]->confidence; ++j) {
      const bool ok = truth.count({p[j]->query, p[j]->candidate}) > 0;
      ok ? ++tp : ++fp;
      if (p[j]->passed) ok ? ++tp_bar : ++fp_bar;
    }
    const double precision = double(tp) / (tp + fp);
    const double recall = m.positives ? double(tp) / m.positives : 0;
    m.curve.push_back({p[i]->confidence, precision, recall, p[i]->tier});
    m.auc += precision * (recall - prev_recall);
    prev_recall = recall;
    if (fp == 0) m.r_at_100p = recall, m.threshold_100p = p[i]->confidence, m.tier_100p = p[i]->tier;
    i = j;
  }
  m.precision_at_bar = tp_bar + fp_bar ? double(tp_bar) / (tp_bar + fp_bar) : 1.0;
  m.recall_at_bar = m.positives ? double(tp_bar) / m.positives : 0;
  return m;
}

int foundAt(const std::vector<LoopPrediction>& predictions, const std::set<std::pair<int, int>>& truth,
            const std::set<int>& queries, double threshold, int tier) {
  int n = 0;
  for (const auto& x : predictions) {
    const bool above = x.tier > tier || (x.tier == tier && x.confidence >= threshold);
    if (x.candidate >= 0 && above && queries.count(x.query) && truth.count({x.query, x.candidate})) ++n;
  }
  return n;
}

}  // namespace binloop
