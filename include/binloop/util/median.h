#pragma once
// The median of a sample, for the evaluation tables and summaries: one definition, so that every table that
// says "median" means the same number.
#include <algorithm>
#include <cmath>
#include <vector>

namespace binloop {

/// The median of the finite values, the mean of the middle two for an even count; NaN when there are none.
inline double median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2) return *mid;
  return 0.5 * (*std::max_element(v.begin(), mid) + *mid);
}

}  // namespace binloop
