// CorrectionHistory: what each loop correction did to each keyframe, for messages that arrive late
// (include/binloop/map/correction_history.h).
#include "binloop/map/correction_history.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace binloop {
namespace {

Pose3 shift(double x) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(x, 0, 0);
  return T;
}

TEST(CorrectionHistory, CorrectionsComposeInOrderFromTheFirstOneMissed) {
  CorrectionHistory h;
  h.begin(1);
  h.note(1, shift(1));
  h.begin(2);
  h.note(1, shift(2));
  EXPECT_EQ(h.applied(), 2u);
  EXPECT_TRUE(h.since(0, 1).isApprox(shift(3)));
  EXPECT_TRUE(h.since(1, 1).isApprox(shift(2)));
  EXPECT_TRUE(h.since(2, 1).isApprox(Pose3::Identity()));
  EXPECT_TRUE(h.since(0, 7).isApprox(Pose3::Identity())) << "a keyframe no correction knew";
  EXPECT_THROW(h.begin(4), std::invalid_argument);
}

// A stage that started after corrections 1-2 counts them as applied, moving nothing, and goes on with 3.
TEST(CorrectionHistory, CatchingUpCountsCorrectionsMadeBeforeTheStageStarted) {
  CorrectionHistory h;
  h.catchUp(2);
  EXPECT_EQ(h.applied(), 2u);
  EXPECT_TRUE(h.since(0, 1).isApprox(Pose3::Identity()));
  h.catchUp(1);  // not ahead: nothing
  EXPECT_EQ(h.applied(), 2u);
  EXPECT_THROW(h.begin(2), std::invalid_argument);
  h.begin(3);
  h.note(1, shift(1));
  EXPECT_TRUE(h.since(2, 1).isApprox(shift(1)));
}

TEST(CorrectionHistory, ALateKeyframeIsRecordedSoThatKeyframesMadeOnItFollow) {
  CorrectionHistory h;
  h.begin(1);
  h.note(1, shift(1));
  EXPECT_TRUE(h.adopt(0, 2, 1).isApprox(shift(1)));
  EXPECT_TRUE(h.adopt(0, 3, 2).isApprox(shift(1)));
}

// Keyframe 2 (parent 1) was culled before correction 1, which therefore names 1 only; keyframe 3 was made
// on 2 before the correction and arrives after it: it moves as 1 did, and only with the chain to follow.
TEST(CorrectionHistory, AnAnchorCulledBeforeTheCorrectionIsFollowedUpItsParents) {
  CorrectionHistory h;
  h.begin(1);
  h.note(1, shift(1));
  auto up = [](SlamKeyframeId k) { return k == 2 ? SlamKeyframeId{1} : kNoId; };
  EXPECT_TRUE(h.adopt(0, 3, 2).isApprox(Pose3::Identity()));
  EXPECT_TRUE(h.adopt(0, 4, 2, up).isApprox(shift(1)));
  EXPECT_TRUE(h.since(0, 4).isApprox(shift(1)));
  auto loop = [](SlamKeyframeId k) { return k == 2 ? SlamKeyframeId{5} : SlamKeyframeId{2}; };
  EXPECT_TRUE(h.adopt(0, 6, 2, loop).isApprox(Pose3::Identity())) << "a cycle ends";
}

}  // namespace
}  // namespace binloop
