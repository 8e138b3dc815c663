#pragma once
// Synthetic descriptor sets for place-recognition tests: random "places" and noisy revisits of them.
#include "binloop/types/binary_descriptor.h"
#include "binloop/util/hash_random.h"
#include "support/random_descriptors.h"

namespace binloop::test {

/// `n` random descriptors of one place, a pure function of (seed, place).
inline Descriptors randomPlace(uint64_t seed, int place, int n = 300) {
  HashRng rng(hashCombine(seed, place));
  Descriptors d(n);
  for (auto& x : d) x = randomDescriptor(rng);
  return d;
}

/// The same place seen again: `flips` random bits of each descriptor flipped, and a fraction dropped.
inline Descriptors revisit(const Descriptors& place, uint64_t seed, int flips = 6, double keep = 0.8) {
  HashRng rng(seed);
  Descriptors out;
  for (auto d : place) {
    if (!rng.chance(keep)) continue;
    for (int i = 0; i < flips; ++i) {
      const int b = rng.below(256);
      d.w[b >> 6] ^= uint64_t{1} << (b & 63);
    }
    out.push_back(d);
  }
  return out;
}

}  // namespace binloop::test
