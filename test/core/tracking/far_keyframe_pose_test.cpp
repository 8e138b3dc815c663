// The pose of a frame 24 m past the keyframes that measured its points
// (include/binloop/tracking/far_keyframe_pose.h): the map's depths of those points are off by metres, the
// frame's own stereo is good, and a third of the matches are wrong.
#include "binloop/tracking/far_keyframe_pose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "binloop/map/keypoint_geometry.h"
#include "binloop/optim/pose_optimizer.h"

namespace binloop {
namespace {

// KITTI 00-02's rectified stereo pair (1241x376, fx 718.9, baseline 0.54 m).
StereoCamera camera() { return kitti00Camera(); }

// A stereo keypoint where the point appears, u, v and u_right moved by `noise_px`.
msg::KeyPoint stereoKeypoint(const StereoCamera& cam, const Eigen::Vector3d& p,
                             const Eigen::Vector3d& noise_px) {
  const double u = cam.fx * p.x() / p.z() + cam.cx;
  msg::KeyPoint k;
  k.x = static_cast<float>(u + noise_px.x());
  k.y = static_cast<float>(cam.fy * p.y() / p.z() + cam.cy + noise_px.y());
  k.right_x = static_cast<float>(u - cam.bf() / p.z() + noise_px.z());
  k.depth = static_cast<float>(cam.bf() / (k.x - k.right_x));
  return k;
}

struct Scene {
  std::vector<FarMatch> matches;
  std::vector<bool> wrong;
  Pose3 truth = Pose3::Identity();  // the frame; the keyframes are 24 m behind it
};

// Points 6-60 m ahead of the frame, in a street 16 m wide. Two keyframes, 24 and 22 m behind, measured
// them with 0.4 px of disparity noise (at 40 m that is 2.5 m of depth); the map's point is their first
// keyframe's stereo point. The frame sees them with 0.3 px noise.
Scene makeScene(int n, double wrong_share, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  const StereoCamera cam = camera();
  Scene sc;
  sc.truth.translation() = Eigen::Vector3d(0.2, 0.0, 24.0);
  Pose3 k1 = Pose3::Identity(), k2 = Pose3::Identity();
  k2.translation() = Eigen::Vector3d(0.1, 0, 2.0);
  while (static_cast<int>(sc.matches.size()) < n) {
    const double z = 6 + 54 * U(g);
    const Eigen::Vector3d p_f((U(g) < 0.5 ? -1 : 1) * (2 + 6 * U(g)), -1.5 + 6 * U(g), z);
    const Eigen::Vector3d p_w = sc.truth * p_f;
    FarMatch m;
    m.keypoint = stereoKeypoint(cam, p_f, Eigen::Vector3d(N(g), N(g), N(g)) * 0.3);
    const msg::KeyPoint& k = m.keypoint;
    if (k.x < 0 || k.x >= cam.width || k.y < 0 || k.y >= cam.height) continue;
    m.inv_sigma2 = 1;
    for (const Pose3* k : {&k1, &k2}) {
      KeyframeSighting s;
      s.keyframe = k == &k1 ? 1 : 2;
      s.T_c_w = k->inverse();
      s.keypoint = stereoKeypoint(cam, s.T_c_w * p_w, Eigen::Vector3d(0, 0, 0.4 * N(g)));
      m.sightings.push_back(s);
    }
    m.p_w = k1 * unprojectKeypoint(m.sightings[0].keypoint, cam);
    const bool wrong = U(g) < wrong_share;
    if (wrong)
      m.keypoint = stereoKeypoint(cam, Eigen::Vector3d(-8 + 16 * U(g), -1.5 + 3 * U(g), 6 + 50 * U(g)),
                                  Eigen::Vector3d::Zero());
    sc.matches.push_back(m);
    sc.wrong.push_back(wrong);
  }
  return sc;
}

Pose3 offBy(const Pose3& T, const Eigen::Vector3d& dt, double yaw_deg) {
  Pose3 out = T;
  out.linear() =
      T.linear() * Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  out.translation() += dt;
  return out;
}

TEST(FarKeyframePose, FindsTheFrameWhereTheMapsDepthsAreMetresOff) {
  const Scene sc = makeScene(60, 0.3, 1);
  const Pose3 prior = offBy(sc.truth, {0.1, 0.1, -0.6}, 0.3);
  const FarPoseResult r = farKeyframePose(camera(), sc.matches, prior, {}, 9);
  ASSERT_TRUE(r.ok) << r.inliers << " inliers";
  EXPECT_LT((r.T_w_c.translation() - sc.truth.translation()).norm(), 0.15);
  EXPECT_LT(rotationDeg(sc.truth.linear().transpose() * r.T_w_c.linear()), 0.2);
  int wrong_kept = 0;
  for (size_t i = 0; i < sc.matches.size(); ++i) wrong_kept += sc.wrong[i] && r.inlier[i];
  EXPECT_LE(wrong_kept, 1);
  EXPECT_GE(r.inliers, 30);
}

// Why the frame's side matters: the ordinary pose optimisation against the map's points, from the same
// prior and on the right matches only, lands farther off. Over many scenes, not one: on a single scene
// either can win (the last session measured 15 of 20 for the two-sided pose).
TEST(FarKeyframePose, BeatsTheOrdinaryPoseOptimisationOverTwentyScenes) {
  std::vector<double> two_sided, ordinary;
  int better = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const Scene sc = makeScene(60, 0.3, seed);
    const Pose3 prior = offBy(sc.truth, {0.1, 0.1, -0.6}, 0.3);
    const FarPoseResult r = farKeyframePose(camera(), sc.matches, prior, {}, 9);
    std::vector<PoseObservation> obs;
    for (size_t i = 0; i < sc.matches.size(); ++i) {
      if (sc.wrong[i]) continue;
      PoseObservation o;
      o.p_w = sc.matches[i].p_w;
      o.uv = {sc.matches[i].keypoint.x, sc.matches[i].keypoint.y};
      o.u_right = sc.matches[i].keypoint.right_x;
      obs.push_back(o);
    }
    const PoseOptimizationResult forward = optimizePose(camera(), prior.inverse(), obs);
    const double mine = r.ok ? (r.T_w_c.translation() - sc.truth.translation()).norm() : 1e9;
    const double theirs = (forward.T_c_w.inverse().translation() - sc.truth.translation()).norm();
    two_sided.push_back(mine);
    ordinary.push_back(theirs);
    better += mine < theirs;
  }
  std::sort(two_sided.begin(), two_sided.end());
  std::sort(ordinary.begin(), ordinary.end());
  EXPECT_LT(two_sided[10], 0.6 * ordinary[10])
      << "medians " << two_sided[10] << " vs " << ordinary[10] << " m";
  EXPECT_GE(better, 13) << "better on " << better << " of 20";
}

TEST(FarKeyframePose, APriorFarFromTheTruthIsNotPassedOff) {
  const Scene sc = makeScene(60, 0.3, 2);
  // 5 m off: beyond max_offset_m, so whatever agrees there is not the frame's pose.
  const FarPoseResult r = farKeyframePose(camera(), sc.matches, offBy(sc.truth, {0, 0, -5}, 0), {}, 9);
  EXPECT_FALSE(r.ok && (r.T_w_c.translation() - sc.truth.translation()).norm() > 0.5);
}

TEST(FarKeyframePose, TooFewMatchesFail) {
  const Scene sc = makeScene(10, 0, 3);
  EXPECT_FALSE(farKeyframePose(camera(), sc.matches, sc.truth, {}, 9).ok);
}

TEST(FarKeyframePose, SameSeedSameAnswer) {
  const Scene sc = makeScene(60, 0.3, 4);
  const Pose3 prior = offBy(sc.truth, {0, 0, 0.5}, -0.2);
  const FarPoseResult a = farKeyframePose(camera(), sc.matches, prior, {}, 5);
  const FarPoseResult b = farKeyframePose(camera(), sc.matches, prior, {}, 5);
  EXPECT_TRUE(a.T_w_c.matrix() == b.T_w_c.matrix());
  EXPECT_EQ(a.inlier, b.inlier);
}

}  // namespace
}  // namespace binloop
