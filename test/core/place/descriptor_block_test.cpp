#include "binloop/place/descriptor_block.h"

#include <gtest/gtest.h>

#include "support/random_descriptors.h"

using namespace binloop;

namespace {

using test::randomDescriptor;

// The reference: one distance at a time, first of the smallest wins.
DescriptorBlock::Nearest byHand(const Descriptors& set, const Desc256& q) {
  DescriptorBlock::Nearest n;
  for (size_t k = 0; k < set.size(); ++k) {
    const int d = hamming(q, set[k]);
    if (d < n.second) {
      if (d < n.best)
        n.second = n.best, n.best = d, n.index = static_cast<int>(k);
      else
        n.second = d;
    }
  }
  return n;
}

void expectSame(const DescriptorBlock::Nearest& a, const DescriptorBlock::Nearest& b,
                const std::string& what) {
  EXPECT_EQ(a.index, b.index) << what;
  EXPECT_EQ(a.best, b.best) << what;
  EXPECT_EQ(a.second, b.second) << what;
}

}  // namespace

// Sizes that are not a multiple of eight exercise the wide search's last, partial step.
TEST(DescriptorBlock, FindsTheNearestAndSecondNearestAsTheByHandLoopDoes) {
  std::cout << "eight-wide search on this CPU: " << (DescriptorBlock::wide() ? "yes" : "no") << "\n";
  HashRng rng(11);
  for (size_t n : {1u, 2u, 7u, 8u, 9u, 63u, 1000u, 2003u}) {
    Descriptors set;
    for (size_t k = 0; k < n; ++k) set.push_back(randomDescriptor(rng));
    const DescriptorBlock block(set);
    ASSERT_EQ(block.size(), n);
    for (int t = 0; t < 20; ++t) {
      // Half the queries are a set member with a few bits changed, so that a clear nearest exists.
      const Desc256 q =
          t % 2 ? test::flipBits(set[rng.below(static_cast<int>(n))], 10, rng) : randomDescriptor(rng);
      const std::string what = "n " + std::to_string(n) + ", query " + std::to_string(t);
      expectSame(block.nearest(q), byHand(set, q), what);
      expectSame(block.nearestPortable(q), byHand(set, q), what);
    }
  }
}

TEST(DescriptorBlock, TiesGoToTheLowestIndexAndAnEmptyBlockFindsNothing) {
  HashRng rng(12);
  Descriptors set;
  for (int k = 0; k < 20; ++k) set.push_back(randomDescriptor(rng));
  const Desc256 q = randomDescriptor(rng);
  set[13] = set[17] = test::flipBits(q, 3, rng);
  const DescriptorBlock block(set);
  for (const auto& n : {block.nearest(q), block.nearestPortable(q)}) {
    EXPECT_EQ(n.index, 13);
    EXPECT_EQ(n.best, n.second);
    EXPECT_LE(n.best, 3);
  }
  const DescriptorBlock empty;
  for (const auto& n : {empty.nearest(q), empty.nearestPortable(q)}) {
    EXPECT_EQ(n.index, -1);
    EXPECT_EQ(n.best, 256);
    EXPECT_EQ(n.second, 256);
  }
  DescriptorBlock one;
  one.add(q);
  EXPECT_EQ(one.nearest(q).best, 0);
  EXPECT_EQ(one.nearest(q).second, 256);
}
