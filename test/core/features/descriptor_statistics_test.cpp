#include "binloop/features/descriptor_statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "binloop/util/hash_random.h"

namespace binloop {
namespace {

Descriptors randomDescriptors(size_t n, uint64_t seed) {
  HashRng rng(seed);
  Descriptors d(n);
  for (auto& x : d)
    for (auto& w : x.w) w = rng.next();
  return d;
}

TEST(BitStatistics, FairIndependentBitsAreUnbiasedAndUncorrelated) {
  const BitStatistics s = bitStatistics(randomDescriptors(20000, 3));
  EXPECT_EQ(s.descriptors, 20000u);
  EXPECT_LT(s.mean_bias, 0.01);
  EXPECT_LT(s.median_abs_correlation, 0.01);
  EXPECT_NEAR(s.random_pair_distance, 128, 1);
}

TEST(BitStatistics, BiasedAndCopiedBitsAreSeen) {
  Descriptors d = randomDescriptors(20000, 4);
  HashRng rng(5);
  for (auto& x : d) {
    x.w[0] |= rng.next() | rng.next();  // word 0: P(1) = 7/8, bias 0.375 on 64 of 256 bits
    x.w[1] = x.w[2];                    // bits 64..127 copy 128..191: correlation 1 for 64 pairs
  }
  const BitStatistics s = bitStatistics(d);
  EXPECT_NEAR(s.mean_bias, 0.375 / 4, 0.01);
  EXPECT_NEAR(s.max_abs_correlation, 1.0, 1e-9);
  EXPECT_LT(s.median_abs_correlation, 0.02);  // 64 copied pairs of 32 640 do not move the median
  EXPECT_LT(s.random_pair_distance, 128 - 10);
}

TEST(BitStatistics, ConstantBitsCountAsUncorrelated) {
  Descriptors d = randomDescriptors(1000, 6);
  for (auto& x : d) x.w[3] = 0;
  const BitStatistics s = bitStatistics(d);
  EXPECT_TRUE(std::isfinite(s.mean_abs_correlation) && std::isfinite(s.median_abs_correlation));
  EXPECT_LE(s.max_abs_correlation, 1.0);
  EXPECT_LT(s.mean_abs_correlation, 0.05);  // 64 constant bits add zeros, not NaNs
  EXPECT_NEAR(s.mean_bias, 0.5 / 4, 0.02);
}

TEST(BitStatistics, RefusesFewerThanTwoDescriptors) {
  EXPECT_THROW(bitStatistics(Descriptors(1)), std::invalid_argument);
}

}  // namespace
}  // namespace binloop
