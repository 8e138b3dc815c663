#pragma once
// Sparse bag-of-words vectors (sorted by word id) and the scores that compare them.
#include <cstdint>
#include <utility>
#include <vector>

namespace binloop {

struct BowEntry {
  uint32_t word;
  float value;
};
using BowVector = std::vector<BowEntry>;  // sorted by word, no duplicates

/// For each node at the feature-vector depth: the indices of the features that passed through it
/// (ORB-SLAM2's "direct index", used to restrict descriptor matching to features sharing a node).
using FeatureVector = std::vector<std::pair<uint32_t, std::vector<uint32_t>>>;

/// DBoW2's L1 score of two L1-normalised vectors: 1 - |a - b|_1 / 2, in [0, 1].
double l1Score(const BowVector& a, const BowVector& b);
void normalizeL1(BowVector& v);

}  // namespace binloop
