#include "binloop/loop/loop_verifier.h"

#include <gtest/gtest.h>

#include "../optim/optim_test_scene.h"
#include "support/random_descriptors.h"
#include "support/stereo_keypoint.h"

namespace binloop {
namespace {

// A street of 600 points seen by the candidate keyframe (at the origin) and by the query keyframe, 1.5 m
// to the side and turned 8 degrees: a revisit in a neighbouring lane. Each point has a descriptor; each
// view flips 3 of its bits. Both keyframes also have 300 keypoints of their own (clutter).
class LoopVerifierTest : public ::testing::Test {
 protected:
  void SetUp() override {
    T_w_q.linear() = Eigen::AngleAxisd(8 * test::kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_w_q.translation() = Eigen::Vector3d(1.5, 0.1, 0.8);
    for (int i = 0; i < 600; ++i) {
      points.emplace_back(rng.uniform(-12, 12), rng.uniform(-3, 1.5), rng.uniform(4, 35));
      Desc256 d;
      for (auto& w : d.w) w = rng.next();
      descs.push_back(d);
    }
  }
  Desc256 view(const Desc256& d) { return test::flipBits(d, 3, rng); }
  // `words` (optional) gets a coarse word per keypoint, as a vocabulary would give: point i's is i % 50 in
  // every view, clutter's a word of its own.
  msg::KeyFrame keyframe(uint64_t id, const Pose3& T_w_c, int shared_points,
                         std::vector<uint32_t>* words = nullptr) {
    msg::KeyFrame kf;
    kf.id = kf.state.id = id;
    kf.camera = cam;
    kf.state.T_w_c = T_w_c;
    auto add = [&](const Eigen::Vector3d& p, const Desc256& d, uint32_t word) {
      if (test::addStereoKeypoint(kf, p, d) && words) words->push_back(word);
    };
    for (int i = 0; i < shared_points; ++i) {
      const Eigen::Vector3d p = T_w_c.inverse() * points[i];
      if (p.z() > 1) add(p, view(descs[i]), static_cast<uint32_t>(i % 50));
    }
    for (int i = 0; i < 300; ++i) {
      Desc256 d;
      for (auto& w : d.w) w = rng.next();
      add(Eigen::Vector3d(rng.uniform(-10, 10), rng.uniform(-3, 2), rng.uniform(4, 40)), d, 1000 + i);
    }
    return kf;
  }

  StereoCamera cam = test::kitti();
  HashRng rng{21};
  Pose3 T_w_q = Pose3::Identity();
  std::vector<Eigen::Vector3d> points;
  Descriptors descs;
};

TEST_F(LoopVerifierTest, ARevisitIsAcceptedWithTheTrueRelativePose) {
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), 600), q = keyframe(2, T_w_q, 600);
  const LoopVerification v = verifyLoop(q, c, {});
  ASSERT_TRUE(v.accepted) << msg::loopStatusName(loopStatusOf(v.rejection)) << ": " << v.detail;
  const Pose3 truth = T_w_q.inverse();  // candidate camera = world
  EXPECT_LT((v.T_query_candidate.translation() - truth.translation()).norm(), 0.05);
  EXPECT_LT(test::rotationErrorDeg(v.T_query_candidate, truth), 0.2);
  EXPECT_GT(v.inliers, 200) << v.detail;
  EXPECT_GE(v.inliers, v.first_inliers / 2);
}

TEST_F(LoopVerifierTest, UnrelatedKeyframesAreRejectedForTooFewMatches) {
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), 0), q = keyframe(2, T_w_q, 0);
  const LoopVerification v = verifyLoop(q, c, {});
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejection, LoopRejection::kTooFewMatches) << v.detail;
}

TEST_F(LoopVerifierTest, MatchesWithoutACommonGeometryFindNoConsensus) {
  msg::KeyFrame c = keyframe(1, Pose3::Identity(), 600);
  const msg::KeyFrame q = keyframe(2, T_w_q, 600);
  // The candidate's descriptors shuffled among its keypoints: every match lands on the wrong 3-D point.
  HashRng shuffle(4);
  for (size_t i = c.descriptors.size(); i > 1; --i)
    std::swap(c.descriptors[i - 1], c.descriptors[shuffle.below(static_cast<int>(i))]);
  const LoopVerification v = verifyLoop(q, c, {});
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejection, LoopRejection::kNoConsensus) << v.detail;
}

TEST_F(LoopVerifierTest, AFewSharedPointsAreTooFewInliers) {
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), 45), q = keyframe(2, T_w_q, 45);
  LoopVerifierParams p;
  p.ransac.min_inliers = 10;
  const LoopVerification v = verifyLoop(q, c, p);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejection, LoopRejection::kTooFewInliers) << v.detail;
  EXPECT_GT(v.inliers, 10) << "the few shared points are found: " << v.detail;
}

// Matching within words finds the revisit; words that split every true pair find nothing; words that do not
// fit the keypoints are not used, and the detail says so.
TEST_F(LoopVerifierTest, MatchingWithinWordsFindsTheRevisitAndOnlyWithinWords) {
  std::vector<uint32_t> cw, qw;
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), 600, &cw), q = keyframe(2, T_w_q, 600, &qw);
  ASSERT_EQ(cw.size(), c.keypoints.size());
  const LoopVerification v = verifyLoop(q, c, {}, qw, cw);
  ASSERT_TRUE(v.accepted) << v.detail;
  EXPECT_TRUE(v.by_words);
  EXPECT_NE(v.detail.find("matches within words"), std::string::npos) << v.detail;
  EXPECT_GT(v.inliers, 200) << v.detail;

  std::vector<uint32_t> split = qw;
  for (uint32_t& w : split) w += 1;  // point i is now in word i % 50 + 1 on one side only
  const LoopVerification none = verifyLoop(q, c, {}, split, cw);
  EXPECT_EQ(none.rejection, LoopRejection::kTooFewMatches) << none.detail;

  LoopVerifierParams all;
  all.match_by_words = false;
  const LoopVerification brute = verifyLoop(q, c, all, split, cw);
  EXPECT_TRUE(brute.accepted) << brute.detail;
  EXPECT_FALSE(brute.by_words);

  const LoopVerification unfit = verifyLoop(q, c, {}, std::vector<uint32_t>(qw.begin(), qw.end() - 1), cw);
  EXPECT_TRUE(unfit.accepted) << unfit.detail;
  EXPECT_FALSE(unfit.by_words);
  EXPECT_NE(unfit.detail.find("words not used"), std::string::npos) << unfit.detail;
}

// From a pose 0.3 m and 0.3 degrees off (a verified loop carried to a keyframe beside its match), the search
// by projection finds the shared points and the true pose; from a keyframe that shares nothing it finds too
// few.
TEST_F(LoopVerifierTest, AVerificationFromAKnownPoseFindsTheTruePose) {
  const msg::KeyFrame c = keyframe(1, Pose3::Identity(), 600), q = keyframe(2, T_w_q, 600);
  const Pose3 truth = T_w_q.inverse();
  Pose3 off = Pose3::Identity();
  off.linear() = Eigen::AngleAxisd(0.3 * test::kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  off.translation() = Eigen::Vector3d(0.2, 0.1, -0.2);
  const LoopVerification v = verifyLoopAt(q, c, off * truth, {});
  ASSERT_TRUE(v.accepted) << v.detail;
  EXPECT_LT((v.T_query_candidate.translation() - truth.translation()).norm(), 0.05);
  EXPECT_LT(test::rotationErrorDeg(v.T_query_candidate, truth), 0.2);
  EXPECT_GT(v.inliers, 200) << v.detail;

  const msg::KeyFrame elsewhere = keyframe(3, Pose3::Identity(), 0);
  const LoopVerification w = verifyLoopAt(q, elsewhere, truth, {});
  EXPECT_FALSE(w.accepted);
  EXPECT_EQ(w.rejection, LoopRejection::kTooFewInliers) << w.detail;
}

}  // namespace
}  // namespace binloop
