#pragma once
// k-majority clustering of binary descriptors (Grana et al.): k-means++ seeding on Hamming distance,
// nearest-centre assignment, and bitwise-majority centres. Used by the vocabulary tree at each node
// and for the flat FAB-MAP vocabulary. Deterministic for a given seed.
#include <cstdint>
#include <vector>

#include "binloop/types/binary_descriptor.h"

namespace binloop {

struct KMajorityParams {
  int k = 10;
  int max_iterations = 10;
  uint64_t seed = 1;
};

struct KMajorityResult {
  std::vector<Desc256> centres;      // no empty cluster: clusters that end empty are dropped
  std::vector<uint32_t> assignment;  // per input descriptor, index into centres
  int iterations = 0;
  int dropped_empty = 0;
};

/// Clusters data[idx[i]]. With fewer distinct descriptors than k, each distinct descriptor becomes a
/// centre (as DBoW2 does at the bottom of a tree).
KMajorityResult kMajority(const Descriptors& data, const std::vector<uint32_t>& idx,
                          const KMajorityParams& p);

/// Bitwise majority of the given descriptors (ties give 0).
Desc256 bitwiseMajority(const Descriptors& data, const uint32_t* idx, size_t n);

/// Index of the nearest of `centres` (lowest index wins a tie) and its distance.
inline uint32_t nearestCentre(const Desc256& x, const Desc256* centres, size_t n, int* dist = nullptr) {
  uint32_t best = 0;
  int best_d = 257;
  // Branch-free selection: which centre wins is unpredictable, and a mispredicted branch per level
  // cost as much as the distances themselves in the vocabulary-tree descent.
  for (size_t c = 0; c < n; ++c) {
    const int d = hamming(x, centres[c]);
    const bool better = d < best_d;
    best_d = better ? d : best_d;
    best = better ? static_cast<uint32_t>(c) : best;
  }
  if (dist) *dist = best_d;
  return best;
}

}  // namespace binloop
