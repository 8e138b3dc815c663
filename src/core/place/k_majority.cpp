#include "binloop/place/k_majority.h"

#include <algorithm>
#include <set>

#include "binloop/util/hash_random.h"

namespace binloop {

Desc256 bitwiseMajority(const Descriptors& data, const uint32_t* idx, size_t n) {
  int counts[Desc256::kBits] = {};
  for (size_t i = 0; i < n; ++i) {
    const Desc256& d = data[idx[i]];
    for (int wi = 0; wi < 4; ++wi) {
      uint64_t v = d.w[wi];
      while (v) {
        counts[wi * 64 + __builtin_ctzll(v)]++;
        v &= v - 1;
      }
    }
  }
  Desc256 out;
  for (int b = 0; b < Desc256::kBits; ++b)
    if (2 * static_cast<size_t>(counts[b]) > n) out.setBit(b);
  return out;
}

namespace {

std::vector<Desc256> seedPlusPlus(const Descriptors& data, const std::vector<uint32_t>& idx, int k,
                                  HashRng& rng) {
  std::vector<Desc256> centres;
  centres.push_back(data[idx[rng.below(static_cast<int>(idx.size()))]]);
  std::vector<double> d2(idx.size());
  for (size_t i = 0; i < idx.size(); ++i) {
    const double d = hamming(data[idx[i]], centres[0]);
    d2[i] = d * d;
  }
  while (static_cast<int>(centres.size()) < k) {
    double total = 0;
    for (double v : d2) total += v;
    if (total <= 0) break;  // every descriptor equals a centre already
    double r = rng.uniform() * total;
    size_t pick = 0;
    for (; pick + 1 < idx.size(); ++pick) {
      r -= d2[pick];
      if (r < 0) break;
    }
    while (d2[pick] == 0) pick = (pick + 1) % idx.size();  // rounding can land on a zero-weight entry
    centres.push_back(data[idx[pick]]);
    for (size_t i = 0; i < idx.size(); ++i) {
      const double d = hamming(data[idx[i]], centres.back());
      d2[i] = std::min(d2[i], d * d);
    }
  }
  return centres;
}

}  // namespace

KMajorityResult kMajority(const Descriptors& data, const std::vector<uint32_t>& idx,
                          const KMajorityParams& p) {
  KMajorityResult res;
  if (idx.empty()) return res;
  if (idx.size() <= static_cast<size_t>(p.k)) {
    std::set<Desc256> distinct;
    for (uint32_t i : idx) distinct.insert(data[i]);
    if (distinct.size() <= static_cast<size_t>(p.k)) {
      res.centres.assign(distinct.begin(), distinct.end());
      res.assignment.resize(idx.size());
      for (size_t i = 0; i < idx.size(); ++i)
        res.assignment[i] = nearestCentre(data[idx[i]], res.centres.data(), res.centres.size());
      return res;
    }
  }
  HashRng rng(p.seed);
  std::vector<Desc256> centres = seedPlusPlus(data, idx, p.k, rng);
  const size_t k = centres.size();
  std::vector<uint32_t> assign(idx.size(), UINT32_MAX);
  std::vector<std::vector<uint32_t>> members(k);
  for (int it = 0; it < std::max(1, p.max_iterations); ++it) {
    bool changed = false;
    for (auto& m : members) m.clear();
    for (size_t i = 0; i < idx.size(); ++i) {
      const uint32_t c = nearestCentre(data[idx[i]], centres.data(), k);
      changed |= c != assign[i];
      assign[i] = c;
      members[c].push_back(idx[i]);
    }
    res.iterations = it + 1;
    if (!changed && it > 0) break;
    for (size_t c = 0; c < k; ++c)
      if (!members[c].empty()) centres[c] = bitwiseMajority(data, members[c].data(), members[c].size());
  }
  // Final assignment to the final centres; clusters that end empty are dropped.
  for (auto& m : members) m.clear();
  for (size_t i = 0; i < idx.size(); ++i) {
    assign[i] = nearestCentre(data[idx[i]], centres.data(), k);
    members[assign[i]].push_back(idx[i]);
  }
  std::vector<uint32_t> remap(k, UINT32_MAX);
  for (size_t c = 0; c < k; ++c) {
    if (members[c].empty()) {
      res.dropped_empty++;
      continue;
    }
    remap[c] = static_cast<uint32_t>(res.centres.size());
    res.centres.push_back(centres[c]);
  }
  res.assignment.resize(idx.size());
  for (size_t i = 0; i < idx.size(); ++i) res.assignment[i] = remap[assign[i]];
  return res;
}

}  // namespace binloop
