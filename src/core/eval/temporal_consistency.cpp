#include "binloop/eval/temporal_consistency.h"

#include <algorithm>
#include <cstdlib>

namespace binloop {

namespace {

// The strongest chain of `chain` links ending at each query, over all offers or only those that passed.
std::vector<LoopPrediction> strongestChains(const std::vector<QueryOffers>& queries, int chain, int max_gap,
                                            bool passed_only) {
  std::vector<LoopPrediction> out;
  out.reserve(queries.size());
  // Per offer of the previous query: weakest[k - 1] = the best weakest link over chains of k links ending
  // there (the last entry: chain links or more), or -1 when there is no such chain.
  struct Ends {
    int frame;
    std::vector<double> weakest;
  };
  std::vector<Ends> prev;
  for (const auto& q : queries) {
    std::vector<Ends> cur;
    LoopPrediction p{q.query, -1, 0};
    for (const Offer& o : q.offers) {
      if (passed_only && !o.passed) continue;
      Ends e{o.frame, std::vector<double>(chain, -1.0)};
      e.weakest[0] = o.confidence;
      for (const Ends& b : prev) {
        if (std::abs(b.frame - o.frame) > max_gap) continue;
        for (int k = 1; k < chain; ++k) {
          const double before = std::max(b.weakest[k - 1], k == chain - 1 ? b.weakest[k] : -1.0);
          if (before >= 0) e.weakest[k] = std::max(e.weakest[k], std::min(o.confidence, before));
        }
      }
      const double full = e.weakest[chain - 1];
      if (full >= 0 && (p.candidate < 0 || full > p.confidence)) p.candidate = o.frame, p.confidence = full;
      cur.push_back(std::move(e));
    }
    out.push_back(p);
    prev = std::move(cur);
  }
  return out;
}

}  // namespace

std::vector<LoopPrediction> consistentPredictions(const std::vector<QueryOffers>& queries, int chain,
                                                  int max_gap) {
  chain = std::max(1, chain);
  std::vector<LoopPrediction> all = strongestChains(queries, chain, max_gap, false);
  const std::vector<LoopPrediction> passed = strongestChains(queries, chain, max_gap, true);
  for (size_t i = 0; i < all.size(); ++i)
    if (passed[i].candidate >= 0) all[i] = passed[i], all[i].passed = true, all[i].tier = 1;
  return all;
}

}  // namespace binloop
