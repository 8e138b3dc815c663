#include "binloop/optim/rigid_alignment.h"

#include <gtest/gtest.h>

#include "optim_test_scene.h"

namespace binloop {
namespace {

Pose3 someMotion() {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, -0.3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(3.0, -0.5, 12.0);
  return T;
}

std::vector<Eigen::Vector3d> cloud(int n, HashRng& rng) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < n; ++i) v.emplace_back(rng.uniform(-8, 8), rng.uniform(-2, 2), rng.uniform(3, 30));
  return v;
}

TEST(RigidAlignment, HornRecoversAnExactTransform) {
  HashRng rng(1);
  const Pose3 T = someMotion();
  const auto b = cloud(10, rng);
  std::vector<Eigen::Vector3d> a;
  for (const auto& p : b) a.push_back(T * p);
  const auto est = hornAlignment(a, b);
  ASSERT_TRUE(est.has_value());
  EXPECT_LT((est->matrix() - T.matrix()).norm(), 1e-9);
  // Three points are enough.
  const auto three = hornAlignment({a[0], a[1], a[2]}, {b[0], b[1], b[2]});
  ASSERT_TRUE(three.has_value());
  EXPECT_LT((three->matrix() - T.matrix()).norm(), 1e-9);
}

TEST(RigidAlignment, HornRefusesCollinearPointsAndTooFewPairs) {
  const std::vector<Eigen::Vector3d> line = {{0, 0, 1}, {0, 0, 2}, {0, 0, 3}, {0, 0, 4}};
  EXPECT_FALSE(hornAlignment(line, line).has_value());
  EXPECT_FALSE(hornAlignment({{1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}}).has_value());
}

TEST(RigidAlignment, RansacFindsTheTransformAmongHalfWrongPairsAndMarksThem) {
  HashRng rng(2);
  const Pose3 T = someMotion();
  const auto b = cloud(200, rng);
  std::vector<Eigen::Vector3d> a;
  std::vector<bool> wrong;
  for (size_t i = 0; i < b.size(); ++i) {
    Eigen::Vector3d p = T * b[i];
    // stereo-like noise: 1 % of the distance
    p += 0.01 * p.norm() / 3 * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
    const bool w = i % 2 == 1;
    if (w) p = T * b[(i * 7 + 13) % b.size()];  // matched to another point
    a.push_back(p);
    wrong.push_back(w);
  }
  const RigidRansacResult r = rigidRansac(a, b, {}, 7);
  ASSERT_TRUE(r.ok);
  EXPECT_LT((r.T_a_b.translation() - T.translation()).norm(), 0.1);
  EXPECT_LT(test::rotationErrorDeg(r.T_a_b, T), 0.3);
  int right = 0, marked_wrong = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    right += !wrong[i] && r.inlier[i];
    marked_wrong += wrong[i] && r.inlier[i];
  }
  EXPECT_GT(right, 90);
  EXPECT_LT(marked_wrong, 3);
  // Same seed, same result.
  const RigidRansacResult again = rigidRansac(a, b, {}, 7);
  EXPECT_EQ(again.inlier, r.inlier);
}

// Half the pairs right: a sample of three right ones comes with probability 1/8 per draw, so 99.9 %
// confidence needs log(0.001) / log(7/8) = 52 draws once the right model is found, not all 300.
TEST(RigidAlignment, RansacStopsOnceConfidentAndRunsEverythingWithoutAConfidence) {
  HashRng rng(5);
  const Pose3 T = someMotion();
  const auto b = cloud(400, rng);
  std::vector<Eigen::Vector3d> a;
  for (size_t i = 0; i < b.size(); ++i) a.push_back(T * b[i % 2 ? (i * 7 + 13) % b.size() : i]);
  const RigidRansacResult r = rigidRansac(a, b, {}, 3);
  ASSERT_TRUE(r.ok);
  EXPECT_GE(r.iterations, 45);  // 52 at exactly half; a wrong pair may land near its point
  EXPECT_LT(r.iterations, 150);
  EXPECT_GE(r.inliers, 200);
  EXPECT_LE(r.inliers, 205);
  RigidRansacParams all;
  all.confidence = 0;
  const RigidRansacResult slow = rigidRansac(a, b, all, 3);
  EXPECT_EQ(slow.iterations, 300);
  EXPECT_EQ(slow.inlier, r.inlier);
}

TEST(RigidAlignment, RansacSaysNoWhenNothingAgrees) {
  HashRng rng(3);
  const auto a = cloud(100, rng), b = cloud(100, rng);
  EXPECT_FALSE(rigidRansac(a, b, {}, 1).ok);
}

}  // namespace
}  // namespace binloop
