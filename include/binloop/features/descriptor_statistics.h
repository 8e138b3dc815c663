#pragma once
// How much of the Hamming space a set of binary descriptors fills: the statistics the ORB paper used to
// choose its learned tests (Rublee et al. 2011, section 4). A test whose bit is 1 on most keypoints, or one
// that copies another test, carries little information; VLAD-style signatures, which sum bits per word,
// suffer most from both.
#include <cstddef>
#include <cstdint>

#include "binloop/types/binary_descriptor.h"

namespace binloop {

struct BitStatistics {
  size_t descriptors = 0;
  double mean_bias = 0;               // mean over the 256 bits of |P(bit = 1) - 0.5|
  double median_abs_correlation = 0;  // over every pair of bits, of |phi| (Pearson's r of two 0/1 variables)
  double mean_abs_correlation = 0;
  double max_abs_correlation = 0;
  double random_pair_distance =
      0;  // mean Hamming distance of seeded random pairs of descriptors (128: ideal)
};

/// A bit that never changes has no correlation with anything (counted as 0). Needs at least 2 descriptors
/// (throws std::invalid_argument otherwise). Deterministic for a seed.
BitStatistics bitStatistics(const Descriptors& d, uint64_t seed = 1, size_t random_pairs = 100000);

}  // namespace binloop
