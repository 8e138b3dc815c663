// Candidates that arrive before their keyframe wait for it and its update, in arrival order; a queue that
// fills up releases its oldest unready.
#include "binloop/loop/candidate_gate.h"

#include <gtest/gtest.h>

#include <string>

namespace binloop {
namespace {

TEST(CandidateGate, ReleasesInArrivalOrderOnceKeyframeAndUpdateAreHere) {
  CandidateGate<std::string> gate;
  gate.push(2, "for 2");
  gate.push(1, "for 1");
  EXPECT_FALSE(gate.next()) << "nothing has arrived";
  gate.keyframeArrived(1);
  gate.updateArrived(1);
  EXPECT_FALSE(gate.next()) << "the candidates for 1 wait behind those for 2";
  gate.keyframeArrived(2);
  EXPECT_FALSE(gate.next()) << "2's update has not come";
  gate.updateArrived(2);
  auto a = gate.next(), b = gate.next();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->candidates, "for 2");
  EXPECT_EQ(b->candidates, "for 1");
  EXPECT_TRUE(a->ready && b->ready);
  EXPECT_FALSE(gate.next());
  EXPECT_EQ(gate.waiting(), 0u);
}

TEST(CandidateGate, AFullQueueReleasesItsOldestUnready) {
  CandidateGate<int> gate(3);
  gate.push(7, 70);  // keyframe 7 is lost on the way
  gate.push(8, 80);
  gate.keyframeArrived(8);
  gate.updateArrived(8);
  EXPECT_FALSE(gate.next());
  gate.push(9, 90);
  auto lost = gate.next();
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->candidates, 70);
  EXPECT_FALSE(lost->ready);
  auto ok = gate.next();
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->candidates, 80);
  EXPECT_TRUE(ok->ready);
  EXPECT_FALSE(gate.next()) << "9 waits, the queue is not full";
  gate.clear();
  EXPECT_EQ(gate.waiting(), 0u);
}

}  // namespace
}  // namespace binloop
