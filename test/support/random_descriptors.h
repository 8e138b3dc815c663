#pragma once
// Random ORB-like descriptors for tests: uniform bits, and a copy with some bits flipped (a re-detection
// of the same corner).
#include "binloop/types/binary_descriptor.h"
#include "binloop/util/hash_random.h"

namespace binloop::test {

inline Desc256 randomDescriptor(HashRng& rng) {
  Desc256 d;
  for (auto& w : d.w) w = rng.next();
  return d;
}

/// `n` bits drawn at random (a bit drawn twice flips back).
inline Desc256 flipBits(Desc256 d, int n, HashRng& rng) {
  for (int i = 0; i < n; ++i) {
    const int bit = rng.below(256);
    d.w[bit / 64] ^= uint64_t{1} << (bit % 64);
  }
  return d;
}

}  // namespace binloop::test
