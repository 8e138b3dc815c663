#include "binloop/place/signature_store.h"

#include <gtest/gtest.h>

#include "binloop/place/place_error.h"
#include "support/test_support.h"

using namespace binloop;

TEST(SignatureStore, DistancesAreThoseOfTheSignaturesPushed) {
  SignatureStore s;
  EXPECT_TRUE(s.empty());
  s.push({0x0, 0x0});
  s.push({0xFF, 0x1});          // 8 + 1 bits set
  s.push({~uint64_t{0}, 0x0});  // 64 bits set
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.words(), 2u);
  EXPECT_EQ(s.distance(s[0], 1), 9);
  EXPECT_EQ(s.distance(s[1], 2), 64 - 8 + 1);
  EXPECT_EQ(s.distance(s[2], 2), 0);
}

// The bar of vlad and hmvlad: the rank-th closest reference, the farthest when there are fewer.
TEST(SignatureStore, TheReferenceBarIsTheDistanceOfTheRankThClosest) {
  SignatureStore s;
  s.push({0x0});
  s.push({0xFF});    // 8 bits from slot 0
  s.push({0x1});     // 1
  s.push({0xFFFF});  // 16
  EXPECT_EQ(referenceBar(s, 0, {1, 2, 3}, 1), 1);
  EXPECT_EQ(referenceBar(s, 0, {1, 2, 3}, 2), 8);
  EXPECT_EQ(referenceBar(s, 0, {1, 2, 3}, 3), 16);
  EXPECT_EQ(referenceBar(s, 0, {1, 2}, 3), 8);
  EXPECT_EQ(referenceBar(s, 0, {}, 3), -1);
  EXPECT_EQ(checkedReferenceRank(1, "vlad"), 1);
  EXPECT_THROW_WITH(checkedReferenceRank(0, "hmvlad"), PlaceError,
                    "hmvlad: reference rank 0, must be at least 1");
}

TEST(SignatureStore, DetailSaysWhenTheFarthestReferenceSetTheBar) {
  EXPECT_EQ(referenceRankText(3, 10), "reference rank 3 of 10");
  EXPECT_EQ(referenceRankText(3, 3), "reference rank 3 of 3");
  EXPECT_EQ(referenceRankText(3, 2), "the farthest of 2 references (rank 3)");
}

TEST(SignatureStore, SignatureOfAnotherLengthIsRefused) {
  SignatureStore s;
  s.push({1, 2, 3});
  EXPECT_THROW_WITH(s.push({1, 2}), PlaceError, "a signature of 2 words among ones of 3");
  EXPECT_THROW_WITH(s.push({}), PlaceError, "empty signature");
  EXPECT_EQ(s.size(), 1u);
}
