#include "binloop/loop/consistency_groups.h"

#include <gtest/gtest.h>

namespace binloop {
namespace {

ConsistencyGroups::Proposal at(SlamKeyframeId c) { return {c, {c - 1, c, c + 1}}; }

TEST(ConsistencyGroups, ACandidateIsAcceptedAfterThreeConsistentQueriesBeforeIt) {
  ConsistencyGroups g(3);
  EXPECT_EQ(g.update({at(10)}).accepted, kNoId);
  EXPECT_EQ(g.update({at(11)}).accepted, kNoId);
  EXPECT_EQ(g.update({at(12)}).accepted, kNoId);
  const auto r = g.update({at(13)});
  EXPECT_EQ(r.accepted, 13u);
  EXPECT_EQ(r.longest, 3);
}

TEST(ConsistencyGroups, AQueryWithoutCandidatesBreaksTheChain) {
  ConsistencyGroups g(3);
  g.update({at(10)});
  g.update({at(11)});
  g.update({});
  g.update({at(12)});
  EXPECT_EQ(g.update({at(13)}).accepted, kNoId);
}

// With max_gap 1 the same drive is accepted: the chain waits one query (hmvlad's case on rendered 00 at 1x,
// include/binloop/loop/consistency_groups.h); two in a row still end it, and places that jump stay apart.
TEST(ConsistencyGroups, WithAGapAChainSurvivesOneQueryThatDoesNotContinueIt) {
  ConsistencyGroups g(2, 1);
  g.update({at(10)});
  g.update({});
  EXPECT_EQ(g.update({at(11)}).longest, 1);
  g.update({at(500)});  // elsewhere: the chain at 11 ages, it does not end
  const auto r = g.update({at(12)});
  EXPECT_EQ(r.longest, 2);
  EXPECT_EQ(r.accepted, 12u);

  ConsistencyGroups h(2, 1);
  h.update({at(10)});
  h.update({});
  h.update({});
  EXPECT_EQ(h.update({at(11)}).longest, 0);
  ConsistencyGroups j(2, 1);
  for (SlamKeyframeId c : {10, 50, 90, 130, 170}) EXPECT_EQ(j.update({at(c)}).accepted, kNoId) << c;
}

TEST(ConsistencyGroups, JumpsBetweenPlacesAreNotConsistent) {
  ConsistencyGroups g(3);
  for (SlamKeyframeId c : {10, 50, 90, 130, 170}) EXPECT_EQ(g.update({at(c)}).accepted, kNoId) << c;
}

TEST(ConsistencyGroups, AWrongFirstCandidateDoesNotHideAConsistentSecond) {
  ConsistencyGroups g(3);
  g.update({at(10)});
  g.update({at(200), at(11)});
  g.update({at(300), at(12)});
  const auto r = g.update({at(400), at(13)});
  EXPECT_EQ(r.accepted, 13u);
}

}  // namespace
}  // namespace binloop
