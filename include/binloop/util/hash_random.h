#pragma once
// Randomness (world generation, k-means seeding) that is the same on every machine and standard library:
// values are pure functions of (seed, stream, index) through SplitMix64, instead of std::*_distribution whose
// results differ between library versions.
#include <cmath>
#include <cstdint>

namespace binloop {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

inline uint64_t hashCombine(uint64_t a, uint64_t b) {
  return splitmix64(a ^ (splitmix64(b) + 0x632BE59BD9B4E019ull));
}

/// A sequential generator for one purpose (e.g. one façade), seeded from a hash.
class HashRng {
 public:
  explicit HashRng(uint64_t seed) : state_(splitmix64(seed)) {}
  uint64_t next() { return state_ = splitmix64(state_); }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n).
  int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
  bool chance(double p) { return uniform() < p; }
  /// Standard normal (Box–Muller).
  double normal() {
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  uint64_t state_;
};

}  // namespace binloop
