#include "binloop/features/descriptor_statistics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "binloop/util/hash_random.h"

namespace binloop {

BitStatistics bitStatistics(const Descriptors& d, uint64_t seed, size_t random_pairs) {
  if (d.size() < 2) throw std::invalid_argument("bit statistics need at least 2 descriptors");
  constexpr int kBits = Desc256::kBits;
  const size_t n = d.size(), words = (n + 63) / 64;
  // Bit columns (bit b of every descriptor, 64 descriptors a word): a pair's joint count is then a popcount
  // of an AND, 256 x 255 / 2 pairs over n / 64 words instead of n x 32 640 tests.
  std::vector<uint64_t> col(static_cast<size_t>(kBits) * words, 0);
  for (size_t i = 0; i < n; ++i) {
    for (int b = 0; b < kBits; ++b)
      if ((d[i].w[b / 64] >> (b % 64)) & 1u) col[b * words + i / 64] |= uint64_t{1} << (i % 64);
  }
  std::vector<double> p(kBits);
  BitStatistics s;
  s.descriptors = n;
  for (int b = 0; b < kBits; ++b) {
    size_t ones = 0;
    for (size_t w = 0; w < words; ++w) ones += __builtin_popcountll(col[b * words + w]);
    p[b] = static_cast<double>(ones) / n;
    s.mean_bias += std::abs(p[b] - 0.5) / kBits;
  }
  std::vector<double> corr;
  corr.reserve(kBits * (kBits - 1) / 2);
  for (int a = 0; a < kBits; ++a) {
    for (int b = a + 1; b < kBits; ++b) {
      size_t both = 0;
      for (size_t w = 0; w < words; ++w)
        both += __builtin_popcountll(col[a * words + w] & col[b * words + w]);
      const double var = p[a] * (1 - p[a]) * p[b] * (1 - p[b]);
      const double r = var > 0 ? (static_cast<double>(both) / n - p[a] * p[b]) / std::sqrt(var) : 0.0;
      corr.push_back(std::abs(r));
    }
  }
  for (double r : corr) {
    s.mean_abs_correlation += r / corr.size();
    s.max_abs_correlation = std::max(s.max_abs_correlation, r);
  }
  std::nth_element(corr.begin(), corr.begin() + corr.size() / 2, corr.end());
  s.median_abs_correlation = corr[corr.size() / 2];
  HashRng rng(seed);
  double sum = 0;
  for (size_t k = 0; k < random_pairs; ++k) {
    const size_t i = rng.next() % n;
    size_t j = rng.next() % (n - 1);
    if (j >= i) ++j;
    sum += hamming(d[i], d[j]);
  }
  s.random_pair_distance = random_pairs ? sum / random_pairs : 0;
  return s;
}

}  // namespace binloop
