#include "binloop/eval/temporal_consistency.h"

#include <algorithm>
#include <cstdlib>

namespace binloop {

std::vector<LoopPrediction> consistentPredictions(const std::vector<QueryOffers>& queries, int chain, int max_gap) {
  chain = std::max(1, chain);
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
    for (const auto& [frame, conf] : q.offers) {
      Ends e{frame, std::vector<double>(chain, -1.0)};
      e.weakest[0] = conf;
      for (const Ends& b : prev) {
        if (std::abs(b.frame - frame) > max_gap) continue;
        for (int k = 1; k < chain; ++k) {
          const double before = std::max(b.weakest[k - 1], k == chain - 1 ? b.weakest[k] : -1.0);
          if (before >= 0) e.weakest[k] = std::max(e.weakest[k], std::min(conf, before));
        }
      }
      const double full = e.weakest[chain - 1];
      if (full >= 0 && (p.candidate < 0 || full > p.confidence)) p.candidate = frame, p.confidence = full;
      cur.push_back(std::move(e));
    }
    out.push_back(p);
    prev = std::move(cur);
  }
  return out;
}

}  // namespace binloop
