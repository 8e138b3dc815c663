#include "binloop/place/float_kmeans.h"

#include <algorithm>
#include <limits>

#include "binloop/util/hash_random.h"

namespace binloop {

uint32_t nearestFloatCentre(const float* x, const float* centres, int n, int dims, float* dist2) {
  uint32_t best = 0;
  float best_d = std::numeric_limits<float>::max();
  for (int c = 0; c < n; ++c) {
    const float d = squaredDistance(x, centres + static_cast<size_t>(c) * dims, dims);
    if (d < best_d) best_d = d, best = static_cast<uint32_t>(c);
  }
  if (dist2) *dist2 = best_d;
  return best;
}

FloatKMeansResult floatKMeans(const std::vector<float>& data, int dims, int k, uint64_t seed,
                              int max_iterations) {
  FloatKMeansResult r;
  const size_t n = data.size() / dims;
  if (n == 0 || k <= 0) return r;
  HashRng rng(seed);
  std::vector<float> c;
  auto row = [&](size_t i) { return data.data() + i * dims; };
  const float* first = row(rng.below(static_cast<int>(n)));
  c.assign(first, first + dims);
  std::vector<double> d2(n);
  for (size_t i = 0; i < n; ++i) d2[i] = squaredDistance(row(i), c.data(), dims);
  int have = 1;
  while (have < k) {
    double total = 0;
    for (double v : d2) total += v;
    if (total <= 0) break;
    double t = rng.uniform() * total;
    size_t pick = 0;
    for (; pick + 1 < n; ++pick) {
      t -= d2[pick];
      if (t < 0) break;
    }
    while (d2[pick] == 0) pick = (pick + 1) % n;
    c.insert(c.end(), row(pick), row(pick) + dims);
    ++have;
    const float* newest = &c[static_cast<size_t>(have - 1) * dims];
    for (size_t i = 0; i < n; ++i) d2[i] = std::min<double>(d2[i], squaredDistance(row(i), newest, dims));
  }
  std::vector<uint32_t> assign(n, UINT32_MAX);
  std::vector<double> sum(static_cast<size_t>(have) * dims);
  std::vector<size_t> count(have);
  for (int it = 0; it < std::max(1, max_iterations); ++it) {
    bool changed = false;
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(count.begin(), count.end(), 0);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t a = nearestFloatCentre(row(i), c.data(), have, dims);
      changed |= a != assign[i];
      assign[i] = a;
      count[a]++;
      for (int j = 0; j < dims; ++j) sum[a * dims + j] += row(i)[j];
    }
    if (!changed && it > 0) break;
    for (int a = 0; a < have; ++a) {
      if (count[a])
        for (int j = 0; j < dims; ++j) c[a * dims + j] = static_cast<float>(sum[a * dims + j] / count[a]);
    }
  }
  std::fill(count.begin(), count.end(), 0);
  for (size_t i = 0; i < n; ++i) count[assign[i] = nearestFloatCentre(row(i), c.data(), have, dims)]++;
  std::vector<uint32_t> remap(have, UINT32_MAX);
  for (int a = 0; a < have; ++a) {
    if (!count[a]) {
      r.dropped_empty++;
      continue;
    }
    remap[a] = static_cast<uint32_t>(r.k++);
    r.centres.insert(r.centres.end(), &c[static_cast<size_t>(a) * dims],
                     &c[static_cast<size_t>(a) * dims] + dims);
  }
  r.assignment.resize(n);
  for (size_t i = 0; i < n; ++i) r.assignment[i] = remap[assign[i]];
  return r;
}

}  // namespace binloop
