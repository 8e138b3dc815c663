#pragma once
// The q-quantile of timings (nearest rank), for the tools' summaries: 0.5 the median, 0.95 the p95.
#include <algorithm>
#include <vector>

namespace binloop {

/// 0 for an empty set.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

}  // namespace binloop
