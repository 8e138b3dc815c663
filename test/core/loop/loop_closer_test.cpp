#include "binloop/loop/loop_closer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "../optim/optim_test_scene.h"
#include "support/random_descriptors.h"
#include "support/stereo_keypoint.h"

namespace binloop {
namespace {

// Keyframes 0..59 drive once round a circle of 40 m radius (4.2 m apart); then the route goes on along a
// straight road. Each of the first keyframes looks at a place of its own: 400 points with descriptors in
// front of it. A keyframe that comes back to place j sees place j's points again (3 bits of each
// descriptor flipped, 300 keypoints of clutter). Estimated poses drift by `drift` metres along x per
// keyframe: est_i = D_i * truth_i.
class LoopCloserTest : public ::testing::Test {
 protected:
  static constexpr double kRadius = 40;
  static constexpr int kLap = 60;

  Pose3 truthOnCircle(double k) const {
    const double a = 2 * test::kPi * k / kLap;
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(kRadius - kRadius * std::cos(a), 0, kRadius * std::sin(a));
    return T;
  }
  // After the lap: straight on from the start, along the circle's first tangent (+z), 4.2 m per keyframe.
  Pose3 truthAfter(int i) const {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(-30, 0, 4.2 * (i - kLap));
    return T;
  }
  Pose3 drifted(const Pose3& truth, int i) const {
    Pose3 D = Pose3::Identity();
    D.translation() = Eigen::Vector3d(drift * i, 0, 0);
    return D * truth;
  }

  void SetUp() override {
    for (int j = 0; j < 6; ++j) {
      std::vector<Eigen::Vector3d> pts;
      Descriptors ds;
      for (int i = 0; i < 400; ++i) {
        pts.emplace_back(rng.uniform(-12, 12), rng.uniform(-3, 1.5), rng.uniform(4, 35));
        Desc256 d;
        for (auto& w : d.w) w = rng.next();
        ds.push_back(d);
      }
      place_points.push_back(pts);  // in the frame of the camera that first sees them
      place_descs.push_back(ds);
    }
  }

  static SlamKeyframeId id(int i) { return (uint64_t{1} << 56) | static_cast<uint64_t>(i + 1); }

  // Keyframe i at `truth`, seeing place `place` (-1: none) laid out in front of `place_pose`; stored with the
  // drifted estimate of index `i`.
  std::shared_ptr<msg::KeyFrame> keyframe(int i, const Pose3& truth, int place, const Pose3& place_pose) {
    auto kf = std::make_shared<msg::KeyFrame>();
    kf->id = kf->state.id = id(i);
    kf->frame_index = static_cast<uint64_t>(3 * i);
    kf->camera = cam;
    kf->state.T_w_c = drifted(truth, i);
    if (i > 0) {
      kf->state.parent = id(i - 1);
      kf->state.covisible.push_back({id(i - 1), 150});
    }
    if (place >= 0) see(*kf, truth, place, place_pose);
    for (int n = 0; n < 300; ++n) {
      Desc256 d;
      for (auto& w : d.w) w = rng.next();
      test::addStereoKeypoint(
          *kf, Eigen::Vector3d(rng.uniform(-10, 10), rng.uniform(-3, 2), rng.uniform(4, 40)), d);
    }
    return kf;
  }
  // The camera at `truth` sees place `place` laid out in front of `place_pose`.
  void see(msg::KeyFrame& kf, const Pose3& truth, int place, const Pose3& place_pose) {
    for (size_t n = 0; n < place_points[place].size(); ++n) {
      test::addStereoKeypoint(kf, truth.inverse() * (place_pose * place_points[place][n]),
                              test::flipBits(place_descs[place][n], 3, rng));
    }
  }

  // The lap: keyframes 0..59, keyframes 0..5 each at its own place.
  void driveLap(LoopCloser& lc) {
    for (int i = 0; i < kLap; ++i)
      lc.addKeyframe(keyframe(i, truthOnCircle(i), i < 6 ? i : -1, truthOnCircle(i)));
  }
  static msg::LoopCandidates proposal(int query, int match) {
    msg::LoopCandidates c;
    c.query = id(query);
    c.accepted = match < 0 ? kNoId : id(match);
    c.model = "test";
    return c;
  }
  static const msg::KeyframeCorrection* correctionOf(const msg::Correction& c, int i) {
    for (const auto& k : c.keyframes)
      if (k.id == id(i)) return &k;
    return nullptr;
  }

  StereoCamera cam = test::kitti();
  HashRng rng{5};
  double drift = 0.02;
  std::vector<std::vector<Eigen::Vector3d>> place_points;
  std::vector<Descriptors> place_descs;
};

// Back at the start, 1 m to the side, after 252 m with 1.2 m of drift: accepted, and the optimised graph
// puts the query where the match says it is and leaves the start where it was.
TEST_F(LoopCloserTest, ARevisitWithinTheDriftBoundIsAcceptedAndCorrectsTheQuery) {
  LoopCloser lc;
  driveLap(lc);
  Pose3 truth = truthOnCircle(0);
  truth.translation().x() += 1.0;
  lc.addKeyframe(keyframe(kLap, truth, 0, truthOnCircle(0)));
  const LoopCloser::Output out = lc.process(proposal(kLap, 0));
  ASSERT_EQ(out.closures.size(), 1u);
  const msg::LoopClosure& c = *out.closures[0];
  ASSERT_EQ(c.status, msg::LoopStatus::kAccepted) << c.detail;
  EXPECT_NEAR(c.correction_m, drift * kLap, 0.1) << c.detail;
  EXPECT_GT(c.drift_bound_m, c.correction_m);
  EXPECT_GE(c.inliers, 40);
  ASSERT_TRUE(out.correction);
  const msg::KeyframeCorrection* q = correctionOf(*out.correction, kLap);
  ASSERT_NE(q, nullptr);
  EXPECT_LT((q->T_w_c_after.translation() - truth.translation()).norm(), 0.1);
  EXPECT_GT((q->T_w_c_before.translation() - truth.translation()).norm(), 1.0);
  const msg::KeyframeCorrection* first = correctionOf(*out.correction, 0);
  ASSERT_NE(first, nullptr);
  EXPECT_LT((first->T_w_c_after.translation() - first->T_w_c_before.translation()).norm(), 1e-9);
  // Halfway round, the graph has spread part of the correction.
  const msg::KeyframeCorrection* half = correctionOf(*out.correction, kLap / 2);
  const double moved = (half->T_w_c_after.translation() - half->T_w_c_before.translation()).norm();
  EXPECT_GT(moved, 0.2);
  EXPECT_LT(moved, drift * kLap);
  EXPECT_EQ(lc.loops().size(), 1u);
}

// A loop closer restarted after mapping applied three corrections gets the map resent with that count: its
// first correction is the fourth, the one mapping waits for (before, it sent the first and mapping refused it
// and every later one).
TEST_F(LoopCloserTest, AStageStartedAfterCorrectionsFollowsTheMapsSequence) {
  LoopCloser lc;
  for (int i = 0; i < kLap; ++i) {
    auto kf = keyframe(i, truthOnCircle(i), i < 6 ? i : -1, truthOnCircle(i));
    kf->corrections_seen = 3;
    kf->resent = true;
    lc.addKeyframe(kf);
  }
  Pose3 truth = truthOnCircle(0);
  truth.translation().x() += 1.0;
  lc.addKeyframe(keyframe(kLap, truth, 0, truthOnCircle(0)));  // a new one, made before it heard of any
  const LoopCloser::Output out = lc.process(proposal(kLap, 0));
  ASSERT_EQ(out.closures.size(), 1u);
  ASSERT_EQ(out.closures[0]->status, msg::LoopStatus::kAccepted) << out.closures[0]->detail;
  ASSERT_TRUE(out.correction);
  EXPECT_EQ(out.correction->sequence, 4u);
}

// Local mapping lost the correction (its process restarted from an autosave made before it): its updates go
// on without it, and after resend_corrections_after_updates of them the closer gives it again; the next
// loop's correction follows it in sequence.
TEST_F(LoopCloserTest, ACorrectionMappingsUpdatesLackIsSentAgain) {
  LoopCloserParams p;
  p.resend_corrections_after_updates = 4;
  LoopCloser lc(p);
  driveLap(lc);
  Pose3 truth = truthOnCircle(0);
  truth.translation().x() += 1.0;
  lc.addKeyframe(keyframe(kLap, truth, 0, truthOnCircle(0)));
  const LoopCloser::Output out = lc.process(proposal(kLap, 0));
  ASSERT_TRUE(out.correction) << out.closures.at(0)->detail;
  msg::LocalMapUpdate u;
  u.corrections_seen = 0;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(lc.apply(u).empty()) << "update " << i;
  const std::vector<msg::CorrectionPtr> again = lc.apply(u);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0], out.correction);
  EXPECT_EQ(lc.correctionsResent(), 1u);
  u.corrections_seen = 1;
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(lc.apply(u).empty());
  EXPECT_EQ(lc.correctionsMade(), 1u);
}

TEST_F(LoopCloserTest, ACandidateFromAnotherPlaceIsRejectedForTooFewMatches) {
  LoopCloser lc;
  driveLap(lc);
  lc.addKeyframe(keyframe(kLap, truthOnCircle(0), 0, truthOnCircle(0)));
  const LoopCloser::Output out = lc.process(proposal(kLap, 4));  // keyframe 4 saw place 4, not place 0
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0]->status, msg::LoopStatus::kTooFewMatches) << out.closures[0]->detail;
  EXPECT_FALSE(out.correction);
  EXPECT_TRUE(lc.loops().empty());
}

// A repeated block: 42 m down the road past the start, a building identical to place 0 stands in the same
// place relative to the camera. Verification accepts it (it is the same structure) but the loop would move
// the query 42 m after 1.2 m of drift (bound 2.3 m): rejected at once. Within 10x the bound it is held, and
// rejected when nothing confirms it.
TEST_F(LoopCloserTest, ARepeatedBlockBeyondTheDriftBoundIsRejected) {
  LoopCloser far;
  driveLap(far);
  const int q = kLap + 10;
  for (int i = kLap; i <= q; ++i) far.addKeyframe(keyframe(i, truthAfter(i), i == q ? 0 : -1, truthAfter(q)));
  LoopCloser::Output out = far.process(proposal(q, 0));
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0]->status, msg::LoopStatus::kBeyondDriftBound) << out.closures[0]->detail;
  EXPECT_GT(out.closures[0]->correction_m, 30);
  EXPECT_FALSE(out.correction);

  LoopCloserParams p;
  p.hold_keyframes = 5;
  p.hold_factor = 100;
  LoopCloser lc(p);
  driveLap(lc);
  for (int i = kLap; i <= q; ++i) lc.addKeyframe(keyframe(i, truthAfter(i), i == q ? 0 : -1, truthAfter(q)));
  out = lc.process(proposal(q, 0));
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0]->status, msg::LoopStatus::kHeld) << out.closures[0]->detail;
  EXPECT_FALSE(out.correction);
  std::optional<msg::LoopStatus> final_status;
  for (int i = q + 1; i < q + 8 && !final_status; ++i) {
    lc.addKeyframe(keyframe(i, truthAfter(i), -1, Pose3::Identity()));
    out = lc.process(proposal(i, -1));
    for (const auto& c : out.closures) final_status = c->status;
    EXPECT_FALSE(out.correction);
  }
  ASSERT_TRUE(final_status) << "no final status within 7 keyframes";
  EXPECT_EQ(*final_status, msg::LoopStatus::kBeyondDriftBound);
  EXPECT_TRUE(lc.loops().empty());
}

// Large drift (18 m over the lap, beyond the 2.3 m bound), but two loops 12 m apart ask for the same
// correction: the first is held, the second confirms it, and both are accepted.
TEST_F(LoopCloserTest, ASecondConsistentLoopConfirmsAHeldOne) {
  drift = 0.3;
  LoopCloser lc;
  driveLap(lc);
  lc.addKeyframe(keyframe(kLap, truthOnCircle(kLap), 0, truthOnCircle(0)));
  LoopCloser::Output out = lc.process(proposal(kLap, 0));
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0]->status, msg::LoopStatus::kHeld) << out.closures[0]->detail;
  for (int i = kLap + 1; i <= kLap + 3; ++i)
    lc.addKeyframe(keyframe(i, truthOnCircle(i), i == kLap + 3 ? 3 : -1, truthOnCircle(3)));
  out = lc.process(proposal(kLap + 3, 3));
  ASSERT_EQ(out.closures.size(), 2u);
  EXPECT_EQ(out.closures[0]->status, msg::LoopStatus::kAccepted) << out.closures[0]->detail;
  EXPECT_EQ(out.closures[1]->status, msg::LoopStatus::kAccepted) << out.closures[1]->detail;
  EXPECT_EQ(out.closures[1]->query, id(kLap));
  EXPECT_EQ(out.closures[1]->query_frame,
            3u * kLap);  // the held loop's own numbers, not the confirming one's
  EXPECT_EQ(out.closures[0]->query_frame, 3u * (kLap + 3));
  ASSERT_TRUE(out.correction);
  EXPECT_EQ(lc.loops().size(), 2u);
  // The odometry edges themselves carry the drift (0.3 m per 4.2 m), so the graph settles between them and
  // the two loops: from 19 m off to under 1 m.
  const msg::KeyframeCorrection* q = correctionOf(*out.correction, kLap + 3);
  EXPECT_GT((q->T_w_c_before.translation() - truthOnCircle(kLap + 3).translation()).norm(), 15);
  EXPECT_LT((q->T_w_c_after.translation() - truthOnCircle(kLap + 3).translation()).norm(), 1.0);
}

// A revisit verified at every keyframe (4.2 m apart), each beyond the bound: the loops that agree with the
// held one but come too soon wait with it instead of replacing it, and the first one 10 m on confirms it.
TEST_F(LoopCloserTest, LoopsTooNearToConfirmAHeldOneWaitWithIt) {
  drift = 0.3;
  LoopCloser lc;
  driveLap(lc);
  std::vector<std::string> seen;  // "status@keyframe" in order
  for (int k = 0; k <= 3; ++k) {
    lc.addKeyframe(keyframe(kLap + k, truthOnCircle(kLap + k), k, truthOnCircle(k)));
    const LoopCloser::Output out = lc.process(proposal(kLap + k, k));
    for (const auto& c : out.closures) {
      for (int i = 0; i <= 3; ++i)
        if (c->query == id(kLap + i))
          seen.push_back(msg::loopStatusName(c->status) + std::string("@") + std::to_string(i));
      if (k < 3) {
        EXPECT_EQ(c->status, msg::LoopStatus::kHeld) << c->detail;
      }
    }
    EXPECT_EQ(static_cast<bool>(out.correction), k == 3);
  }
  const std::vector<std::string> expected{"held@0",     "held@1",   "held@2",  "accepted@3",
                                          "accepted@0", "agreed@1", "agreed@2"};
  EXPECT_EQ(seen, expected);
  EXPECT_EQ(lc.loops().size(), 2u);

  // Nothing confirms them: the held loop and the one that agreed with it are rejected together.
  LoopCloserParams p;
  p.hold_keyframes = 4;
  LoopCloser alone(p);
  driveLap(alone);
  seen.clear();
  for (int k = 0; k < 6; ++k) {
    const int place = k < 2 ? k : -1;
    alone.addKeyframe(keyframe(kLap + k, truthOnCircle(kLap + k), place, truthOnCircle(k)));
    for (const auto& c : alone.process(proposal(kLap + k, place)).closures)
      seen.push_back(msg::loopStatusName(c->status) + std::string("@") +
                     std::to_string(c->query == id(kLap) ? 0 : 1));
  }
  const std::vector<std::string> rejected{"held@0", "held@1", "beyond_drift_bound@0", "beyond_drift_bound@1"};
  EXPECT_EQ(seen, rejected);
  EXPECT_TRUE(alone.loops().empty());
}

TEST_F(LoopCloserTest, ALoopStillHeldWhenTheInputEndsGetsItsFinalStatus) {
  drift = 0.3;
  LoopCloser lc;
  driveLap(lc);
  for (int k = 0; k < 2; ++k) {
    lc.addKeyframe(keyframe(kLap + k, truthOnCircle(kLap + k), k, truthOnCircle(k)));
    for (const auto& c : lc.process(proposal(kLap + k, k)).closures)
      EXPECT_EQ(c->status, msg::LoopStatus::kHeld) << c->detail;
  }
  const LoopCloser::Output end = lc.finish();
  ASSERT_EQ(end.closures.size(), 2u);
  for (const auto& c : end.closures) {
    EXPECT_EQ(c->status, msg::LoopStatus::kBeyondDriftBound);
    EXPECT_NE(c->detail.find("input ended"), std::string::npos) << c->detail;
  }
  EXPECT_EQ(end.closures[0]->query, id(kLap));  // the held loop first, then the one that waited with it
  EXPECT_FALSE(end.correction);
  EXPECT_TRUE(lc.loops().empty());
  EXPECT_TRUE(lc.finish().closures.empty());  // nothing is held any more
}

TEST_F(LoopCloserTest, AnExternalLoopIsVerifiedBeforeItIsApplied) {
  LoopCloser lc;
  driveLap(lc);
  lc.addKeyframe(keyframe(kLap, truthOnCircle(kLap), 1, truthOnCircle(1)));
  LoopCloser::Output wrong = lc.addExternalLoop(id(kLap), id(2), "operator");
  ASSERT_EQ(wrong.closures.size(), 1u);
  EXPECT_EQ(wrong.closures[0]->model, "operator");
  EXPECT_EQ(wrong.closures[0]->status, msg::LoopStatus::kTooFewMatches);
  EXPECT_FALSE(wrong.correction);
  LoopCloser::Output unknown = lc.addExternalLoop(id(kLap), id(500));
  EXPECT_EQ(unknown.closures[0]->status, msg::LoopStatus::kUnknownKeyframe);
  LoopCloser::Output right = lc.addExternalLoop(id(kLap), id(1), "operator");
  EXPECT_EQ(right.closures[0]->status, msg::LoopStatus::kAccepted) << right.closures[0]->detail;
  EXPECT_TRUE(right.correction);
}

// The detector proposes keyframe 3, whose place the query sees from 8 m away; keyframe 1, which keyframe 3
// shares points with, stood 0.5 m from the query and sees what the query sees up close. The loop edge is
// measured there.
TEST_F(LoopCloserTest, AFarMatchIsAnchoredAtItsCovisibleKeyframeNearestTheQuery) {
  for (const double reanchor_min_m : {5.0, 0.0}) {
    LoopCloserParams p;
    p.reanchor_min_m = reanchor_min_m;
    LoopCloser lc(p);
    for (int i = 0; i < kLap; ++i) {
      auto kf = keyframe(i, truthOnCircle(i), i < 6 ? i : -1, truthOnCircle(i));
      if (i == 3) kf->state.covisible.push_back({id(1), 120});
      lc.addKeyframe(kf);
    }
    Pose3 truth = truthOnCircle(1);
    truth.translation().x() += 0.5;
    auto q = keyframe(kLap, truth, 3, truthOnCircle(3));
    see(*q, truth, 1, truthOnCircle(1));
    lc.addKeyframe(q);
    const LoopCloser::Output out = lc.process(proposal(kLap, 3));
    ASSERT_EQ(out.closures.size(), 1u);
    const msg::LoopClosure& c = *out.closures[0];
    ASSERT_EQ(c.status, msg::LoopStatus::kAccepted) << c.detail;
    if (reanchor_min_m > 0) {
      EXPECT_EQ(c.match, id(1)) << c.detail;
      EXPECT_EQ(c.match_frame, 3u);
      EXPECT_NE(c.detail.find("anchored at keyframe"), std::string::npos) << c.detail;
      EXPECT_LT(c.T_query_match.translation().norm(), 1.0);
    } else {
      EXPECT_EQ(c.match, id(3)) << c.detail;
      EXPECT_GT(c.T_query_match.translation().norm(), 7.0);
    }
    EXPECT_EQ(lc.loops().back().candidate, c.match);
  }
}

// The detector still proposes keyframe 1 after mapping culled it; its parent, keyframe 0, stands for it.
TEST_F(LoopCloserTest, AProposalOfACulledKeyframeIsVerifiedAgainstItsParent) {
  LoopCloser lc;
  driveLap(lc);
  msg::LocalMapUpdate u;
  u.culled_keyframes = {id(1)};
  lc.apply(u);
  lc.addKeyframe(keyframe(kLap, truthOnCircle(0), 0, truthOnCircle(0)));
  const LoopCloser::Output out = lc.process(proposal(kLap, 1));
  ASSERT_EQ(out.closures.size(), 1u);
  const msg::LoopClosure& c = *out.closures[0];
  EXPECT_EQ(c.status, msg::LoopStatus::kAccepted) << c.detail;
  EXPECT_EQ(c.match, id(0));
  EXPECT_NE(c.detail.find("keyframe 2 was culled, its spanning-tree parent 1 stands for it"),
            std::string::npos)
      << c.detail;
}

TEST_F(LoopCloserTest, AMalformedKeyframeIsRefused) {
  LoopCloser lc;
  auto kf = std::make_shared<msg::KeyFrame>(*keyframe(0, truthOnCircle(0), 0, truthOnCircle(0)));
  kf->descriptors.pop_back();
  EXPECT_THROW(lc.addKeyframe(kf), std::invalid_argument);
}

}  // namespace
}  // namespace binloop
