#include "binloop/eval/temporal_consistency.h"

#include <gtest/gtest.h>

using namespace binloop;

TEST(TemporalConsistency, NeedsThreeConsistentQueriesAndTakesTheWeakestLink) {
  // Queries 10..14; a revisit of frames ~100 from query 11 on, and a lone strong false match at query 12.
  const std::vector<QueryOffers> q{{10, {{500, 0.9}}},
                                   {11, {{100, 1.5}}},
                                   {12, {{101, 1.2}, {700, 3.0}}},
                                   {13, {{103, 1.4}}},
                                   {14, {{300, 2.0}}}};
  const auto p = consistentPredictions(q, 3, 4);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_EQ(p[0].candidate, -1);
  EXPECT_EQ(p[1].candidate, -1);
  EXPECT_EQ(p[2].candidate, -1);  // 700 has no predecessor; 100 -> 101 is only two links
  EXPECT_EQ(p[3].candidate, 103);
  EXPECT_DOUBLE_EQ(p[3].confidence, 1.2);  // 1.5, 1.2, 1.4: the weakest link
  EXPECT_EQ(p[4].candidate, -1);           // 300 is 197 frames from 103: the chain breaks
}

TEST(TemporalConsistency, PrefersTheChainWithTheStrongerWeakestLink) {
  // Two ways to reach 205 in three links: through 201 (weak, 0.2) or through 204 (0.8).
  const std::vector<QueryOffers> q{
      {1, {{200, 1.0}}}, {2, {{201, 0.2}, {204, 0.8}}}, {3, {{205, 0.9}}}, {4, {{207, 0.7}}}};
  const auto p = consistentPredictions(q, 3, 4);
  EXPECT_EQ(p[2].candidate, 205);
  EXPECT_DOUBLE_EQ(p[2].confidence, 0.8);
  EXPECT_DOUBLE_EQ(p[3].confidence, 0.7);  // a chain longer than 3 keeps its best weakest link
}

TEST(TemporalConsistency, ChainOfOneIsTheRawPrediction) {
  const std::vector<QueryOffers> q{{1, {{50, 0.4}, {60, 0.7}}}};
  const auto p = consistentPredictions(q, 1, 4);
  EXPECT_EQ(p[0].candidate, 60);
  EXPECT_DOUBLE_EQ(p[0].confidence, 0.7);
}

TEST(TemporalConsistency, PassedOnlyWhenEveryLinkPassedItsBar) {
  // The same chain, once with a middle link that did not pass its model's bar (a best rejected keyframe).
  for (const bool middle_passed : {true, false}) {
    const std::vector<QueryOffers> q{
        {1, {{100, 1.0, true}}}, {2, {{101, 0.9, middle_passed}}}, {3, {{102, 1.1, true}}}};
    const auto p = consistentPredictions(q, 3, 4);
    EXPECT_EQ(p[2].candidate, 102);
    EXPECT_DOUBLE_EQ(p[2].confidence, 0.9);
    EXPECT_EQ(p[2].passed, middle_passed);
    EXPECT_EQ(p[2].tier, middle_passed ? 1 : 0);
  }
}

TEST(TemporalConsistency, ChainsOfCandidatesComeFirst) {
  // A strong chain through a rejected keyframe (200..202) and a weaker chain of candidates (500..502) end at
  // the same query: the candidates' chain is the prediction, as ORB-SLAM2 only chains candidates.
  const std::vector<QueryOffers> q{{1, {{200, 3.0, true}, {500, 1.1, true}}},
                                   {2, {{201, 2.5, false}, {501, 1.2, true}}},
                                   {3, {{202, 3.0, true}, {502, 1.3, true}}}};
  const auto p = consistentPredictions(q, 3, 4);
  EXPECT_EQ(p[2].candidate, 502);
  EXPECT_DOUBLE_EQ(p[2].confidence, 1.1);
  EXPECT_EQ(p[2].tier, 1);
}
