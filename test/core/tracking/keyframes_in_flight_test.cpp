#include "binloop/tracking/keyframes_in_flight.h"

#include <gtest/gtest.h>

using namespace binloop;

TEST(KeyframesInFlight, AnswersTakeKeyframesOutOfFlightAndCorrectionsDoNot) {
  KeyframesInFlight f(5);
  f.sent(1);
  f.sent(2);
  EXPECT_EQ(f.count(), 2);
  f.heard(3);  // a loop correction: mapping is alive but answered no keyframe
  EXPECT_EQ(f.count(), 2);
  f.answered(4);
  f.answered(5);
  f.answered(6);  // an update for a keyframe given up or of an earlier tracker: never below 0
  EXPECT_EQ(f.count(), 0);
  EXPECT_EQ(f.givenUp(), 0u);
}

TEST(KeyframesInFlight, GivenUpAfterTheTimeoutWithoutAnAnswer) {
  KeyframesInFlight f(5);
  f.sent(10);
  f.sent(11);
  EXPECT_EQ(f.giveUpIfStale(15.9, true), "") << "4.9 s since mapping was last heard from";
  f.heard(14);
  EXPECT_EQ(f.giveUpIfStale(18.9, true), "") << "a correction counts as contact";
  const std::string why = f.giveUpIfStale(19.5, true);
  EXPECT_NE(why.find("answered none of the last 2 keyframes for 5.0 s"), std::string::npos) << why;
  EXPECT_EQ(f.count(), 0);
  EXPECT_EQ(f.givenUp(), 2u);
  f.sent(20);
  EXPECT_EQ(f.giveUpIfStale(24, true), "") << "the clock starts again with the next keyframe";
}

TEST(KeyframesInFlight, GivenUpAtOnceWhenNoMappingListens) {
  KeyframesInFlight f(5);
  EXPECT_EQ(f.giveUpIfStale(100, false), "") << "nothing in flight, nothing to give up";
  f.sent(100);
  const std::string why = f.giveUpIfStale(100.1, false);
  EXPECT_NE(why.find("no local mapping subscribes"), std::string::npos) << why;
  EXPECT_EQ(f.count(), 0);
  EXPECT_EQ(f.givenUp(), 1u);
  f.sent(101);
  f.clear();  // a new tracker
  EXPECT_EQ(f.count(), 0);
  EXPECT_EQ(f.givenUp(), 1u) << "a reset gives nothing up";
}
