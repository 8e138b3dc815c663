#include "binloop/place/bow_vector.h"

#include <cmath>

namespace binloop {

double l1Score(const BowVector& a, const BowVector& b) {
  // Only common words change the sum: |x - y| - |x| - |y| is 0 when either is 0.
  double s = 0;
  for (size_t i = 0, j = 0; i < a.size() && j < b.size();) {
    if (a[i].word < b[j].word) {
      ++i;
    } else if (b[j].word < a[i].word) {
      ++j;
    } else {
      const double x = a[i].value, y = b[j].value;
      s += std::fabs(x - y) - std::fabs(x) - std::fabs(y);
      ++i, ++j;
    }
  }
  return -0.5 * s;
}

void normalizeL1(BowVector& v) {
  double n = 0;
  for (const auto& e : v) n += std::fabs(e.value);
  if (n > 0)
    for (auto& e : v) e.value = static_cast<float>(e.value / n);
}

}  // namespace binloop
