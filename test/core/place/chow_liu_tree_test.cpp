#include "binloop/place/chow_liu_tree.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "binloop/util/hash_random.h"

using namespace binloop;

TEST(ChowLiuTree, MutualInformationByHand) {
  EXPECT_NEAR(ChowLiuTree::mutualInformation(100, 50, 50, 25), 0.0, 1e-12);            // independent
  EXPECT_NEAR(ChowLiuTree::mutualInformation(100, 50, 50, 50), std::log(2.0), 1e-12);  // identical
  EXPECT_NEAR(ChowLiuTree::mutualInformation(100, 50, 50, 0), std::log(2.0), 1e-12);   // complementary
}

TEST(ChowLiuTree, RecoversTheTreeThatGeneratedTheData) {
  // Word 0 is a fair coin; 1 and 2 copy 0, 3 copies 1, 4 copies 2, each copy flipped with 10-20 %
  // probability; word 5 is independent. The tree must hold exactly the generating edges plus one edge to 5.
  const int parent[6] = {-1, 0, 0, 1, 2, -1};
  const double flip[6] = {0, 0.1, 0.15, 0.1, 0.2, 0};
  HashRng rng(5);
  std::vector<std::vector<uint32_t>> images(4000);
  for (auto& im : images) {
    bool z[6];
    for (int i = 0; i < 6; ++i) {
      z[i] = parent[i] < 0 ? rng.chance(0.5) : (z[parent[i]] != rng.chance(flip[i]));
      if (z[i]) im.push_back(static_cast<uint32_t>(i));
    }
  }
  const ChowLiuTree t = ChowLiuTree::learn(images, 6);
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t i = 0; i < 6; ++i)
    if (i != t.root()) edges.insert({std::min(i, t.parent(i)), std::max(i, t.parent(i))});
  for (auto e : std::set<std::pair<uint32_t, uint32_t>>{{0, 1}, {0, 2}, {1, 3}, {2, 4}})
    EXPECT_TRUE(edges.count(e)) << e.first << "-" << e.second;
  EXPECT_EQ(edges.size(), 5u);
  // Conditionals follow the generating model: p(z3 = 1 | z1 = 1) ≈ 0.9.
  const uint32_t child = t.parent(3) == 1 ? 3 : 1, par = t.parent(3) == 1 ? 1 : 3;
  ASSERT_EQ(t.parent(child), par);
  EXPECT_NEAR(t.conditional(child, true), 0.9, 0.03);
  EXPECT_NEAR(t.conditional(child, false), 0.1, 0.03);
  EXPECT_NEAR(t.marginal(5), 0.5, 0.03);
}
