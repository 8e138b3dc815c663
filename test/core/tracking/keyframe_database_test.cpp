#include "binloop/tracking/keyframe_database.h"

#include <gtest/gtest.h>

#include "binloop/util/hash_random.h"

namespace binloop {
namespace {

// Places are sets of 300 random descriptors; a revisit sees the same ones with a few bits flipped.
class KeyframeDatabaseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int p = 0; p < 6; ++p) {
      Descriptors d(300);
      for (auto& x : d)
        for (auto& w : x.w) w = rng.next();
      places.push_back(d);
    }
    VocabTreeParams vp;
    vp.k = 8;
    vp.levels = 3;
    voc = std::make_shared<VocabularyTree>(VocabularyTree::train(places, vp));
  }
  Descriptors revisit(int place) {
    Descriptors d = places[place];
    for (auto& x : d) x.w[rng.below(4)] ^= uint64_t{1} << rng.below(64);
    return d;
  }
  static std::vector<SlamKeyframeId> none(SlamKeyframeId) { return {}; }

  HashRng rng{11};
  std::vector<Descriptors> places;
  std::shared_ptr<VocabularyTree> voc;
};

TEST_F(KeyframeDatabaseTest, ARevisitFindsItsPlaceFirst) {
  KeyframeDatabase db(voc);
  for (int p = 0; p < 6; ++p) db.add(100 + p, places[p]);
  for (int p = 0; p < 6; ++p) {
    const auto c = db.candidates(revisit(p), 3, none);
    ASSERT_FALSE(c.empty()) << "place " << p;
    EXPECT_EQ(c.front(), static_cast<SlamKeyframeId>(100 + p));
  }
}

TEST_F(KeyframeDatabaseTest, ARemovedKeyframeIsNeverACandidate) {
  KeyframeDatabase db(voc);
  for (int p = 0; p < 6; ++p) db.add(100 + p, places[p]);
  db.remove(102);
  EXPECT_EQ(db.size(), 5u);
  for (SlamKeyframeId k : db.candidates(revisit(2), 6, none)) EXPECT_NE(k, 102u);
}

TEST_F(KeyframeDatabaseTest, APlaceSeenByCovisibleKeyframesBeatsASingleLookAlike) {
  // Keyframes 1-3 see half of place 0 each; keyframe 4, not covisible with them, 60 % of it. Alone, 4
  // scores best; with their neighbours' scores summed, the group of 1-3 gives the first candidate.
  KeyframeDatabase db(voc);
  auto part = [&](int place, size_t from, size_t n) {
    return Descriptors(places[place].begin() + from, places[place].begin() + from + n);
  };
  db.add(1, part(0, 0, 150));
  db.add(2, part(0, 75, 150));
  db.add(3, part(0, 150, 150));
  db.add(4, part(0, 50, 180));  // 180 vs 150: within the 80 % common-word cut
  auto neighbours = [](SlamKeyframeId k) {
    if (k == 4) return std::vector<SlamKeyframeId>{};
    std::vector<SlamKeyframeId> n;
    for (SlamKeyframeId j = 1; j <= 3; ++j)
      if (j != k) n.push_back(j);
    return n;
  };
  const Descriptors query = revisit(0);
  const auto alone = db.candidates(query, 1, none);
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone.front(), 4u) << "the scenario needs 4 to be the best single keyframe";
  const auto grouped = db.candidates(query, 1, neighbours);
  ASSERT_EQ(grouped.size(), 1u);
  EXPECT_NE(grouped.front(), 4u);
}

TEST_F(KeyframeDatabaseTest, EmptyDatabaseOrQueryGivesNothing) {
  KeyframeDatabase db(voc);
  EXPECT_TRUE(db.candidates(places[0], 5, none).empty());
  db.add(1, places[0]);
  EXPECT_TRUE(db.candidates({}, 5, none).empty());
}

}  // namespace
}  // namespace binloop
