#pragma once
// The one statistic every benchmark table prints: the median of several runs.
#include <algorithm>
#include <vector>

namespace binloop::bench {

/// The middle value (the upper one of an even count); 0 when there is none.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace binloop::bench
