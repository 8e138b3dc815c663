#pragma once
// Lloyd's k-means with k-means++ seeding on float rows, seeded (HashRng) so that training repeats bit
// for bit. Used for the VLAD vocabularies (on binary-expanded descriptors) and the PQ codebooks.
#include <cstdint>
#include <vector>

namespace binloop {

struct FloatKMeansResult {
  std::vector<float> centres;  // k × dims, row-major
  std::vector<uint32_t> assignment;
  int k = 0;
  int dropped_empty = 0;
};

/// data is n × dims row-major. Returns fewer than k centres when clusters end empty (they are dropped)
/// or when there are fewer rows than k.
FloatKMeansResult floatKMeans(const std::vector<float>& data, int dims, int k, uint64_t seed,
                              int max_iterations = 20);

/// Squared L2 distance of two rows of `dims` floats.
inline float squaredDistance(const float* a, const float* b, int dims) {
  float s = 0;
  for (int i = 0; i < dims; ++i) {
    const float d = a[i] - b[i];
    s += d * d;
  }
  return s;
}

/// Index of the nearest of n centres (row-major) to x.
uint32_t nearestFloatCentre(const float* x, const float* centres, int n, int dims, float* dist2 = nullptr);

}  // namespace binloop
