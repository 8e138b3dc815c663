#pragma once
// How a model's candidates are ranked across queries: the `confidence` of a Candidate (docs/loop_models.md,
// "Ranking loops"). A model's bar (its reference keyframes' score) says whether a keyframe beats the query's
// own neighbours; the thesis and ORB-SLAM2 accept on it. Dividing by the bar alone ranks badly across
// queries: a query whose neighbours share almost nothing with it (a new room, open ground, a sharp turn) has
// a tiny bar, and any weak match then gets a huge ratio and outranks true loops. So the bar is bounded before
// dividing: an L1-score bar never counts as lower than `score_floor`, a distance bar never as farther than
// `distance_cap` of the signature's bits. Below the bound, confidence follows the raw score. The bounds
// were chosen on the tuning sets (real_tune, rendered 06 and 05) and checked on the held-out ones
// (real_heldout, rendered 00); docs/loop_models.md, "Ranking loops", has the table and the sweep.
#include <algorithm>

namespace binloop {

struct RankingParams {
  // hbow: L1 score (TF-IDF, k=10 L=6 vocabularies). 0.03 since ORB's learned pattern (0.02 before): R@100P
  // 06 0.934 -> 0.967, 05 0.612 -> 0.662, real_tune 0.731 -> 0.769; held-out 00 0.326 -> 0.669.
  double score_floor = 0.03;
  // hbow: nor lower than the score this share of the database stays below. A query that shares as much
  // with a tenth of the keyframes as with its best match is generic (a featureless wall, a repeated
  // facade), and its tiny reference score would otherwise rank its guess high. 0.9: real_heldout 0.833 ->
  // 0.933; rendered 06, 05, 00 and real_tune unchanged (docs/results/2026-11-27-fabmap-ranking.md).
  double score_background_quantile = 0.9;
  double distance_cap = 0.35;  // vlad, hmvlad, vladpq: fraction of the signature's bits
};

/// Similarity scores (higher is better) against a bar of the same units.
inline double scoreConfidence(double score, double bar, double floor) {
  return score / std::max({bar, floor, 1e-9});
}

/// Distances (lower is better) against a bar distance; `cap` in the same units (bits).
inline double distanceConfidence(double bar, double dist, double cap) {
  return (std::min(bar, cap) + 1.0) / (dist + 1.0);
}

}  // namespace binloop
