#include "binloop/optim/pose_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "optim_test_scene.h"

using namespace binloop;
using namespace binloop::test;

namespace {

// A camera 10 m into the world, turned 20 deg, seeing `n` points at 3-50 m with Gaussian pixel noise of
// `pixel_sigma` at octave 0 (scaled by the octave, as the weights assume).
std::vector<PoseObservation> observe(const StereoCamera& cam, const Pose3& T_c_w, int n, double pixel_sigma,
                                     HashRng& rng) {
  std::vector<PoseObservation> obs;
  while (static_cast<int>(obs.size()) < n) {
    const Eigen::Vector3d p_w =
        backProject(cam, T_c_w, rng.uniform(0, cam.width), rng.uniform(0, cam.height), rng.uniform(3, 50));
    const Measurement m = measure(cam, T_c_w * p_w, pixel_sigma, true, rng);
    if (m.visible) obs.push_back({p_w, m.uv, m.u_right, m.inv_sigma2});
  }
  return obs;
}

Pose3 truePose() {
  Pose3 T_w_c = Pose3::Identity();
  T_w_c.linear() = Eigen::AngleAxisd(20 * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_w_c.translation() = Eigen::Vector3d(2, -0.5, 10);
  return T_w_c;
}

// [centre error; rotation error about the world axes] of an estimated T_w_c.
Eigen::Matrix<double, 6, 1> errorOf(const Pose3& est, const Pose3& truth) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = est.translation() - truth.translation();
  const Eigen::AngleAxisd aa(est.linear() * truth.linear().transpose());
  e.tail<3>() = aa.angle() * aa.axis();
  return e;
}

}  // namespace

// The covariance it predicts is the spread the pose really has: 300 frames, each with its own noise, and
// the variance of each of the six errors within a third of the predicted one.
TEST(PoseCovariance, PredictsTheSpreadOfOptimisedPoses) {
  const StereoCamera cam = kitti();
  const Pose3 T_w_c = truePose();
  HashRng rng(11);
  Matrix6d predicted = Matrix6d::Zero(), seen = Matrix6d::Zero();
  const int trials = 300;
  double sigma_px = 0;
  for (int t = 0; t < trials; ++t) {
    const std::vector<PoseObservation> obs = observe(cam, T_w_c.inverse(), 120, 1.0, rng);
    const PoseOptimizationResult r = optimizePose(cam, perturb(T_w_c.inverse(), 0.5, 0.1, rng), obs);
    std::vector<PoseObservation> inliers;
    for (size_t i = 0; i < obs.size(); ++i)
      if (!r.outlier[i]) inliers.push_back(obs[i]);
    const PoseCovariance c = poseCovariance(cam, r.T_c_w.inverse(), inliers);
    ASSERT_TRUE(c.valid);
    predicted += c.covariance / trials;
    sigma_px += c.sigma_px / trials;
    const Eigen::Matrix<double, 6, 1> e = errorOf(r.T_c_w.inverse(), T_w_c);
    seen += e * e.transpose() / trials;
  }
  std::cout << "predicted sd: " << predicted.diagonal().cwiseSqrt().transpose()
            << "\nseen sd:      " << seen.diagonal().cwiseSqrt().transpose() << "\nsigma_px " << sigma_px
            << "\n";
  // Outliers cut at chi2 95 % trim the residuals a little: the measured sigma is just under the true 1 px.
  EXPECT_GT(sigma_px, 0.85);
  EXPECT_LT(sigma_px, 1.05);
  for (int i = 0; i < 6; ++i) {
    EXPECT_GT(predicted(i, i), 0.67 * seen(i, i)) << "component " << i;
    EXPECT_LT(predicted(i, i), 1.5 * seen(i, i)) << "component " << i;
  }
}

TEST(PoseCovariance, ScalesWithTheNoiseAndShrinksWithMorePoints) {
  const StereoCamera cam = kitti();
  const Pose3 T_w_c = truePose();
  HashRng rng(12);
  const std::vector<PoseObservation> few = observe(cam, T_w_c.inverse(), 100, 2.0, rng);
  const std::vector<PoseObservation> many = observe(cam, T_w_c.inverse(), 400, 2.0, rng);
  const PoseCovariance a = poseCovariance(cam, T_w_c, few), b = poseCovariance(cam, T_w_c, many);
  ASSERT_TRUE(a.valid && b.valid);
  EXPECT_NEAR(a.sigma_px, 2.0, 0.3) << "the residuals' own spread sets the scale";
  EXPECT_LT(b.covariance.trace(), 0.5 * a.covariance.trace())
      << "four times the points, about a quarter of the variance";
}

TEST(PoseCovariance, TooFewObservationsGiveNone) {
  const StereoCamera cam = kitti();
  HashRng rng(13);
  const Pose3 T_w_c = truePose();
  const std::vector<PoseObservation> two = observe(cam, T_w_c.inverse(), 2, 1.0, rng);
  EXPECT_FALSE(poseCovariance(cam, T_w_c, two).valid);
  EXPECT_FALSE(poseCovariance(cam, T_w_c, {}).valid);
}
