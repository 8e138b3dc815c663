#include "binloop/optim/pose_optimizer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <memory>

#include "binloop/optim/reprojection_costs.h"
#include "optim_test_scene.h"
#include "support/test_support.h"

using namespace binloop;
using namespace binloop::test;

namespace {

struct Frame {
  StereoCamera cam = kitti();
  Pose3 T_c_w_true;
  std::vector<PoseObservation> obs;
  std::vector<bool> gross;  // per observation: a planted wrong association
};

// One frame of a camera 10 m into the world, turned 20 deg to the left, seeing `n` points at 3-50 m;
// `outlier_share` of them wrongly associated. `stereo` = false makes every observation monocular.
Frame makeFrame(int n, double outlier_share, bool stereo, uint64_t seed, double pixel_sigma = 0.5) {
  Frame f;
  HashRng rng(seed);
  Pose3 T_w_c = Pose3::Identity();
  T_w_c.linear() = Eigen::AngleAxisd(20 * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_w_c.translation() = Eigen::Vector3d(2, -0.5, 10);
  f.T_c_w_true = T_w_c.inverse();
  while (static_cast<int>(f.obs.size()) < n) {
    const Eigen::Vector3d p_w = backProject(f.cam, f.T_c_w_true, rng.uniform(0, f.cam.width),
                                            rng.uniform(0, f.cam.height), rng.uniform(3, 50));
    Measurement m = measure(f.cam, f.T_c_w_true * p_w, pixel_sigma, stereo, rng);
    if (!m.visible) continue;
    const bool gross = rng.chance(outlier_share);
    if (gross) corrupt(m, rng);
    f.obs.push_back({p_w, m.uv, m.u_right, m.inv_sigma2});
    f.gross.push_back(gross);
  }
  return f;
}

int count(const std::vector<bool>& v) { return static_cast<int>(std::count(v.begin(), v.end(), true)); }

void expectRecovered(const Frame& f, const PoseOptimizationResult& r) {
  EXPECT_LT(centreError(r.T_c_w, f.T_c_w_true), 0.01);
  EXPECT_LT(rotationErrorDeg(r.T_c_w, f.T_c_w_true), 0.05);
  ASSERT_EQ(r.outlier.size(), f.obs.size());
  int missed = 0, false_alarms = 0, inliers = 0;
  for (size_t i = 0; i < f.obs.size(); ++i) {
    missed += f.gross[i] && !r.outlier[i];
    false_alarms += !f.gross[i] && r.outlier[i];
    inliers += !r.outlier[i];
  }
  EXPECT_EQ(missed, 0) << "planted outliers not flagged";
  // 0.5 px noise is a fifth of the threshold's sigma: almost no true inlier should be rejected.
  EXPECT_LE(false_alarms, 0.01 * (f.obs.size() - count(f.gross)));
  EXPECT_EQ(r.num_inliers, inliers);
  EXPECT_LT(r.final_cost, r.initial_cost);
  // The remaining cost is the noise's: E[chi2] = 0.25 per row.
  EXPECT_LT(r.final_cost, 0.5 * 3 * 0.25 * inliers * 1.5);
}

}  // namespace

TEST(PoseOptimizer, RecoversPerturbedStereoPoseAndFlagsGrossOutliers) {
  const Frame f = makeFrame(600, 0.2, true, 1);
  int stereo = 0;
  for (const auto& o : f.obs) stereo += o.u_right >= 0;
  ASSERT_GT(stereo, 100);  // a mix, as on KITTI: close points stereo, far ones mono
  ASSERT_GT(static_cast<int>(f.obs.size()) - stereo, 100);
  for (uint64_t trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE(trial);
    HashRng rng(100 + trial);
    const Pose3 start = perturb(f.T_c_w_true, 3, 0.3, rng);
    const PoseOptimizationResult r = optimizePose(f.cam, start, f.obs);
    expectRecovered(f, r);
    EXPECT_EQ(r.rounds_run, 4);
    // Gauss-Newton converges fast on a pose: Ceres stops a round on its function tolerance.
    EXPECT_GE(r.iterations, 2);
    EXPECT_LE(r.iterations, 40);
  }
}

// Loop verification solves on 200 of its ~1000 pairs: the pose comes out as well and every observation,
// those not in the solve included, is judged.
TEST(PoseOptimizer, SolvingOnASpreadSubsetRecoversThePoseAndJudgesEveryObservation) {
  const Frame f = makeFrame(1500, 0.2, true, 4);
  PoseOptimizerParams p;
  p.max_solve_observations = 200;
  for (uint64_t trial = 0; trial < 3; ++trial) {
    SCOPED_TRACE(trial);
    HashRng rng(300 + trial);
    expectRecovered(f, optimizePose(f.cam, perturb(f.T_c_w_true, 3, 0.3, rng), f.obs, p));
  }
  p.max_solve_observations = 2;
  EXPECT_THROW(optimizePose(f.cam, f.T_c_w_true, f.obs, p), std::invalid_argument);
}

TEST(PoseOptimizer, MonocularOnlyObservations) {
  const Frame f = makeFrame(600, 0.2, false, 2);
  for (const auto& o : f.obs) ASSERT_LT(o.u_right, 0);
  for (uint64_t trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE(trial);
    HashRng rng(200 + trial);
    expectRecovered(f, optimizePose(f.cam, perturb(f.T_c_w_true, 3, 0.3, rng), f.obs));
  }
}

TEST(PoseOptimizer, BitIdenticalAcrossRuns) {
  const Frame f = makeFrame(800, 0.2, true, 3);
  HashRng rng(3);
  const Pose3 start = perturb(f.T_c_w_true, 3, 0.3, rng);
  const PoseOptimizationResult a = optimizePose(f.cam, start, f.obs);
  const PoseOptimizationResult b = optimizePose(f.cam, start, f.obs);
  EXPECT_EQ(0, std::memcmp(a.T_c_w.matrix().data(), b.T_c_w.matrix().data(), 16 * sizeof(double)));
  EXPECT_EQ(0, std::memcmp(&a.final_cost, &b.final_cost, sizeof(double)));
  EXPECT_EQ(0, std::memcmp(&a.initial_cost, &b.initial_cost, sizeof(double)));
  EXPECT_EQ(a.outlier, b.outlier);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(PoseOptimizer, PointsBehindTheCameraAreOutliers) {
  Frame f = makeFrame(300, 0.0, true, 4);
  // Three points behind the camera, "seen" at plausible pixels.
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d p_w = f.T_c_w_true.inverse() * Eigen::Vector3d(i - 1.0, 0.5, -5.0 - i);
    f.obs.push_back({p_w, Eigen::Vector2d(600 + 10 * i, 180), -1, 1});
    f.gross.push_back(true);
  }
  HashRng rng(4);
  const PoseOptimizationResult r = optimizePose(f.cam, perturb(f.T_c_w_true, 1, 0.1, rng), f.obs);
  expectRecovered(f, r);
  for (size_t i = f.obs.size() - 3; i < f.obs.size(); ++i) EXPECT_TRUE(r.outlier[i]) << i;
}

TEST(PoseOptimizer, ParametersAreHonoured) {
  const Frame f = makeFrame(300, 0.2, true, 5);
  HashRng rng(5);
  const Pose3 start = perturb(f.T_c_w_true, 1, 0.1, rng);
  PoseOptimizerParams p;
  p.rounds = 1;
  p.iterations_per_round = 1;
  const PoseOptimizationResult one = optimizePose(f.cam, start, f.obs, p);
  EXPECT_EQ(one.rounds_run, 1);
  EXPECT_EQ(one.iterations, 1);
  // A threshold no residual can pass flags everything.
  p = {};
  p.chi2_mono = p.chi2_stereo = 1e-12;
  const PoseOptimizationResult none = optimizePose(f.cam, start, f.obs, p);
  EXPECT_EQ(none.num_inliers, 0);
  EXPECT_EQ(count(none.outlier), static_cast<int>(f.obs.size()));
  EXPECT_EQ(none.rounds_run, 1);  // nothing left for round 2
}

TEST(PoseOptimizer, TooFewObservationsReturnThePoseAsGiven) {
  const Frame f = makeFrame(2, 0.0, true, 6);
  HashRng rng(6);
  const Pose3 start = perturb(f.T_c_w_true, 1, 0.1, rng);
  const PoseOptimizationResult r = optimizePose(f.cam, start, f.obs);
  EXPECT_EQ(0, std::memcmp(r.T_c_w.matrix().data(), start.matrix().data(), 16 * sizeof(double)));
  EXPECT_EQ(r.rounds_run, 0);
  EXPECT_EQ(r.outlier.size(), 2u);
  const PoseOptimizationResult empty = optimizePose(f.cam, start, {});
  EXPECT_EQ(empty.num_inliers, 0);
  EXPECT_TRUE(empty.outlier.empty());
}

TEST(PoseOptimizer, InvalidInputThrows) {
  const Frame f = makeFrame(20, 0.0, true, 7);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto with = [&](auto edit) {
    std::vector<PoseObservation> obs = f.obs;
    edit(obs[5]);
    return obs;
  };
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, with([&](auto& o) { o.p_w.x() = nan; })),
                    std::invalid_argument, "observation 5: point p_w is not finite");
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, with([&](auto& o) { o.uv.y() = nan; })),
                    std::invalid_argument, "pixel uv is not finite");
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, with([&](auto& o) { o.u_right = nan; })),
                    std::invalid_argument, "u_right is not finite");
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, with([&](auto& o) { o.inv_sigma2 = 0; })),
                    std::invalid_argument, "inv_sigma2 must be positive");
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, with([&](auto& o) { o.inv_sigma2 = -1; })),
                    std::invalid_argument, "inv_sigma2 must be positive");
  StereoCamera cam = f.cam;
  cam.fx = 0;
  EXPECT_THROW_WITH(optimizePose(cam, f.T_c_w_true, f.obs), std::invalid_argument, "focal lengths");
  cam = f.cam;
  cam.baseline_m = 0;
  EXPECT_THROW_WITH(optimizePose(cam, f.T_c_w_true, f.obs), std::invalid_argument, "positive baseline");
  Pose3 bad = f.T_c_w_true;
  bad.translation().z() = nan;
  EXPECT_THROW_WITH(optimizePose(f.cam, bad, f.obs), std::invalid_argument,
                    "initial pose T_c_w is not finite");
  bad = f.T_c_w_true;
  bad.linear() *= 1.1;
  EXPECT_THROW_WITH(optimizePose(f.cam, bad, f.obs), std::invalid_argument, "no rotation matrix");
  PoseOptimizerParams p;
  p.rounds = 0;
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, f.obs, p), std::invalid_argument, "rounds");
  p = {};
  p.chi2_stereo = nan;
  EXPECT_THROW_WITH(optimizePose(f.cam, f.T_c_w_true, f.obs, p), std::invalid_argument, "chi2_stereo");
}

// The residual is the projection of T_c_w(xi) * p_w, with T_c_w(xi) = poseFromIncrement(xi, T0), in both the
// bundle-adjustment and the pose-only functors.
TEST(ReprojectionCosts, ResidualIsTheWhitenedProjectionError) {
  const StereoCamera cam = kitti();
  const ProjectionConstants k(cam);
  HashRng rng(8);
  const Pose3 T0 = perturb(Pose3::Identity(), 10, 1, rng);
  const double xi[6] = {0.02, -0.01, 0.03, 0.1, -0.2, 0.05};
  const Pose3 T = poseFromIncrement(xi, T0);
  const Eigen::Vector3d p_w = backProject(cam, T, 400, 150, 12);
  const Eigen::Vector2d uv(403, 148);
  const double u_right = 360, inv_sigma2 = 1 / 1.44;

  const Eigen::Vector3d p_c = T * p_w;
  const double u = cam.fx * p_c.x() / p_c.z() + cam.cx, v = cam.fy * p_c.y() / p_c.z() + cam.cy;
  const Eigen::Vector3d e(uv.x() - u, uv.y() - v, u_right - (u - cam.bf() / p_c.z()));
  const double expected_stereo = inv_sigma2 * e.squaredNorm(),
               expected_mono = inv_sigma2 * e.head<2>().squaredNorm();
  EXPECT_NEAR(u, 400, 1e-9);

  bool in_front = false;
  EXPECT_NEAR(StereoReprojectionCost(k, T0, uv, u_right, inv_sigma2).chi2(xi, p_w.data(), &in_front),
              expected_stereo, 1e-9);
  EXPECT_TRUE(in_front);
  EXPECT_NEAR(MonoReprojectionCost(k, T0, uv, -1, inv_sigma2).chi2(xi, p_w.data(), &in_front), expected_mono,
              1e-9);
  EXPECT_NEAR(StereoPoseOnlyCost(k, T0, p_w, uv, u_right, inv_sigma2).chi2(xi, &in_front), expected_stereo,
              1e-9);
  EXPECT_NEAR(MonoPoseOnlyCost(k, T0, p_w, uv, -1, inv_sigma2).chi2(xi, &in_front), expected_mono, 1e-9);

  const Eigen::Vector3d behind = T.inverse() * Eigen::Vector3d(1, 0, -3);
  StereoReprojectionCost(k, T0, uv, u_right, inv_sigma2).chi2(xi, behind.data(), &in_front);
  EXPECT_FALSE(in_front);

  // xi = 0 is the anchor pose itself, bit for bit.
  const double zero[6] = {0, 0, 0, 0, 0, 0};
  const Pose3 same = poseFromIncrement(zero, T0);
  EXPECT_TRUE(same.matrix() == T0.matrix());
}

// Bundle adjustment's closed-form Jacobians (linearizeReprojection) are the automatic ones of the Ceres
// functor at xi = 0, for stereo and mono, far and near points, and a rotated camera.
TEST(ReprojectionCosts, ClosedFormJacobiansAreTheAutomaticOnes) {
  const StereoCamera cam = kitti();
  const ProjectionConstants k(cam);
  HashRng rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T = perturb(Pose3::Identity(), 30, 5, rng);
    const Eigen::Vector3d p_w =
        backProject(cam, T, rng.uniform(0, cam.width), rng.uniform(0, cam.height), rng.uniform(2, 80));
    const Eigen::Vector2d uv(rng.uniform(0, cam.width), rng.uniform(0, cam.height));
    const double u_right = uv.x() - rng.uniform(1, 40), inv_sigma2 = 1 / std::pow(1.2, 2 * rng.below(8));
    const double obs[3] = {uv.x(), uv.y(), u_right};
    for (const bool stereo : {true, false}) {
      SCOPED_TRACE(::testing::Message() << "trial " << trial << (stereo ? " stereo" : " mono"));
      const LinearizedReprojection l = linearizeReprojection(k, T, p_w, obs, std::sqrt(inv_sigma2), stereo);
      ASSERT_TRUE(l.in_front);
      const int rows = stereo ? 3 : 2;
      double r[3] = {0, 0, 0}, J_xi[3 * 6] = {}, J_p[3 * 3] = {};
      double* jacobians[2] = {J_xi, J_p};
      const double xi[6] = {0, 0, 0, 0, 0, 0};
      const double* params[2] = {xi, p_w.data()};
      std::unique_ptr<ceres::CostFunction> f(
          stereo ? static_cast<ceres::CostFunction*>(
                       StereoReprojectionCost::create(k, T, uv, u_right, inv_sigma2))
                 : MonoReprojectionCost::create(k, T, uv, -1, inv_sigma2));
      ASSERT_TRUE(f->Evaluate(params, r, jacobians));
      for (int i = 0; i < rows; ++i) {
        const double scale = 1 + l.J_pose.row(i).cwiseAbs().maxCoeff();
        EXPECT_NEAR(l.r(i), r[i], 1e-9 * (1 + std::abs(r[i])));
        for (int j = 0; j < 6; ++j)
          EXPECT_NEAR(l.J_pose(i, j), J_xi[6 * i + j], 1e-9 * scale) << i << "," << j;
        for (int j = 0; j < 3; ++j)
          EXPECT_NEAR(l.J_point(i, j), J_p[3 * i + j], 1e-9 * scale) << i << "," << j;
      }
      if (!stereo) {
        EXPECT_TRUE(l.J_pose.row(2).isZero() && l.J_point.row(2).isZero() && l.r(2) == 0);
      }
      EXPECT_NEAR(l.chi2, l.r.squaredNorm(), 1e-12);
    }
  }
}
