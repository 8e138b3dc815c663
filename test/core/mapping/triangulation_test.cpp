#include "binloop/mapping/triangulation.h"

#include <gtest/gtest.h>

#include "../optim/optim_test_scene.h"

namespace binloop {
namespace {

using test::kitti;

// A camera at `x` metres along the world x axis looking down +z (world = camera axes).
Pose3 cameraAt(double x, double z = 0) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(x, 0, z);
  return T;
}

msg::KeyPoint keypointOf(const StereoCamera& cam, const Pose3& T_w_c, const Eigen::Vector3d& p_w, int octave,
                         bool stereo) {
  const Eigen::Vector3d p = T_w_c.inverse() * p_w;
  msg::KeyPoint k;
  k.x = static_cast<float>(cam.fx * p.x() / p.z() + cam.cx);
  k.y = static_cast<float>(cam.fy * p.y() / p.z() + cam.cy);
  k.octave = static_cast<uint8_t>(octave);
  if (stereo) {
    k.right_x = static_cast<float>(k.x - cam.bf() / p.z());
    k.depth = static_cast<float>(p.z());
  }
  return k;
}

TEST(TriangulationTest, LinearTriangulationRecoversTheTruePointWithoutNoise) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(2.0, 1.0);
  const Eigen::Vector3d X(1.5, -0.7, 12.0);
  const msg::KeyPoint ka = keypointOf(cam, a, X, 0, false), kb = keypointOf(cam, b, X, 0, false);
  const auto t =
      triangulateLinear(a.inverse(), b.inverse(), {(ka.x - cam.cx) / cam.fx, (ka.y - cam.cy) / cam.fy},
                        {(kb.x - cam.cx) / cam.fx, (kb.y - cam.cy) / cam.fy});
  ASSERT_TRUE(t.has_value());
  EXPECT_LT((*t - X).norm(), 1e-3);  // float keypoints: ~1e-4 px rounding at 12 m
}

TEST(TriangulationTest, MonocularPairWithParallaxGivesThePoint) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(3.0);
  const Eigen::Vector3d X(1.0, 0.5, 25.0);  // beyond stereo range: only two views can place it
  const msg::KeyPoint ka = keypointOf(cam, a, X, 0, false), kb = keypointOf(cam, b, X, 0, false);
  Eigen::Vector3d out;
  ASSERT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kOk);
  EXPECT_LT((out - X).norm(), 0.02);
}

TEST(TriangulationTest, NearlyParallelMonocularRaysAreRefused) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(0.5);
  const Eigen::Vector3d X(0, 0, 200.0);  // 0.14 degrees of parallax
  const msg::KeyPoint ka = keypointOf(cam, a, X, 0, false), kb = keypointOf(cam, b, X, 0, false);
  Eigen::Vector3d out;
  EXPECT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kParallel);
}

TEST(TriangulationTest, StereoDepthWinsWhenItsBaselineSeesMoreThanTheRays) {
  const StereoCamera cam = kitti();
  // The keyframes are 0.3 m apart, the stereo pair 0.54 m: a's stereo point is the better estimate.
  const Pose3 a = cameraAt(0), b = cameraAt(0, 0.3);
  const Eigen::Vector3d X(2.0, 0.3, 8.0);
  msg::KeyPoint ka = keypointOf(cam, a, X, 0, true);
  ka.depth = 8.05f;  // a stereo depth slightly off, so its use is visible in the result
  ka.right_x = static_cast<float>(ka.x - cam.bf() / 8.05);
  const msg::KeyPoint kb = keypointOf(cam, b, X, 0, false);
  Eigen::Vector3d out;
  ASSERT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kOk);
  EXPECT_NEAR(out.z(), 8.05, 1e-4);
}

TEST(TriangulationTest, WrongMatchFailsTheReprojectionTest) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(3.0);
  const Eigen::Vector3d X(1.0, 0.5, 15.0);
  const msg::KeyPoint ka = keypointOf(cam, a, X, 0, false);
  msg::KeyPoint kb = keypointOf(cam, b, X, 0, false);
  kb.y += 6;  // off the epipolar line: the rays do not meet
  Eigen::Vector3d out;
  EXPECT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kReprojection);
}

TEST(TriangulationTest, RaysMeetingBehindTheCamerasAreRefused) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(3.0);
  // Keypoints of a point 15 m in front, swapped between the views: the rays diverge and meet behind.
  const Eigen::Vector3d X(1.5, 0.5, 15.0);
  const msg::KeyPoint ka = keypointOf(cam, b, X, 0, false), kb = keypointOf(cam, a, X, 0, false);
  Eigen::Vector3d out;
  EXPECT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kBehind);
}

TEST(TriangulationTest, OctavesThatContradictTheDistancesAreRefused) {
  const StereoCamera cam = kitti();
  const Pose3 a = cameraAt(0), b = cameraAt(3.0);
  const Eigen::Vector3d X(1.0, 0.5, 15.0);  // about as far from both
  const msg::KeyPoint ka = keypointOf(cam, a, X, 0, false), kb = keypointOf(cam, b, X, 5, false);
  Eigen::Vector3d out;
  EXPECT_EQ(triangulatePair({&a, &cam, &ka}, {&b, &cam, &kb}, ScalePyramid(1.2f, 8), {}, &out),
            TriangulationResult::kScale);
}

}  // namespace
}  // namespace binloop
